#!/usr/bin/env python3
"""Where the avg plugin's VPLs land in the U room (scenes/u_room.gltf).

Reads the CSV files that `gibench render --method avg` writes with
GIBENCH_AVG_VPLS=FILE (one live VPL a line: position, normal, power,
bounce) and prints, per file, how many VPLs and what share of the VPL power
lie in each part of the room's floor plan (scenes/README.md): the near arm
(x < 2, z < 6: the light's), the corridor (z > 6), its end in front of the
far arm (corridor with x > 4) and the far arm (x > 4, z < 6: the one the
default camera looks down, lit only indirectly). VPLs lie up to a voxel
behind their surface (pushed into the voxel, §III-B), so the split is made
at the middles: x = 3 between the arms and z = 5.8 between an arm and the
corridor (the wall block between the arms ends at z = 6). Power
is the luminance of the flux (0.2126 R + 0.7152 G + 0.0722 B). Stdlib only.

Usage: plugins/avg/vpl_regions.py FILE.csv... (Markdown table on stdout)
"""

import csv
import sys


def region(x, z):
    if z > 5.8:
        return "corridor_far" if x > 4.0 else "corridor"
    return "far" if x > 3.0 else "near"


def main(argv):
    if len(argv) < 2:
        sys.stderr.write("usage: avg_vpl_regions.py FILE.csv...\n")
        return 2
    print("| file | live VPLs | near arm | corridor (x > 4) | corridor VPLs by bounce 1/2/3 | far arm "
          "| far-arm VPLs by bounce 1/2/3 | power share: corridor | corridor x > 4 | far arm |")
    print("|---|---:|---:|---:|---|---:|---|---:|---:|---:|")
    for path in argv[1:]:
        try:
            with open(path, newline="") as f:
                rows = list(csv.DictReader(f))
        except OSError as e:
            sys.stderr.write("avg_vpl_regions.py: %s\n" % e)
            return 1
        count = {"near": 0, "corridor": 0, "corridor_far": 0, "far": 0}
        power = dict.fromkeys(count, 0.0)
        far_bounce = [0, 0, 0, 0]
        cor_bounce = [0, 0, 0, 0]
        for r in rows:
            reg = region(float(r["x"]), float(r["z"]))
            lum = 0.2126 * float(r["r"]) + 0.7152 * float(r["g"]) + 0.0722 * float(r["b"])
            count[reg] += 1
            power[reg] += lum
            if reg == "far":
                far_bounce[min(int(r["bounce"]), 3)] += 1
            elif reg.startswith("corridor"):
                cor_bounce[min(int(r["bounce"]), 3)] += 1
        total = sum(power.values())
        share = {k: 100.0 * v / total if total else 0.0 for k, v in power.items()}
        print("| %s | %d | %d | %d (%d) | %d / %d / %d | %d | %d / %d / %d | %.2f %% | %.2f %% | %.2f %% |" % (
            path, len(rows), count["near"], count["corridor"] + count["corridor_far"], count["corridor_far"],
            cor_bounce[1], cor_bounce[2], cor_bounce[3], count["far"], far_bounce[1], far_bounce[2], far_bounce[3],
            share["corridor"] + share["corridor_far"], share["corridor_far"], share["far"]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
