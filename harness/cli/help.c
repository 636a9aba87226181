/* The help of every command: `gibench help CMD` and `gibench CMD --help`
 * (docs/commands.md, says the same at length). */
#include "cli.h"

#include <string.h>

typedef struct command_help {
    const char *name, *text;
} command_help;

static const command_help helps[] = {
    {"methods",
     "usage: gibench methods [ID] [--json]\n"
     "List the method plugins found (the build's plugins/ and GIBENCH_PLUGIN_PATH): id, paper,\n"
     "caps, bounce count, every parameter with its type, default, range and meaning, and the\n"
     "debug buffers that render writes on request. With ID: that method only.\n"
     "  --json   the same as JSON (what bash completion and scripts read)\n"},
    {"info",
     "usage: gibench info SCENE [--json]\n"
     "Describe a glTF scene: objects, triangles, materials, lights, cameras, animation, bounds.\n"
     "  --json   as JSON\n"},
    {"render",
     "usage: gibench render --scene S --method M --out FILE [--out FILE]... [options]\n"
     "Render one method on one scene and camera; write the image and, with --timings, its "
     "timings.\n"
     "  --scene S              glTF scene (.gltf/.glb)\n"
     "  --method M             method id (gibench methods)\n"
     "  --out FILE             .exr (linear float), .pfm or .png (tonemapped); up to 4\n"
     "  --camera NAME|#k       the scene's camera (default: its first); view:FILE.json, a view "
     "saved\n"
     "                         by gibench view: its camera and moved objects and lights only\n"
     "  --size WxH             image size (default 256x256)\n"
     "  --param k=v            a method parameter (repeatable; gibench methods lists them)\n"
     "  --frames N             frames of a still view (progressive methods converge); default 1\n"
     "  --warmup N             frames left out of the timing statistics\n"
     "  --time T               scene time in seconds (animation)\n"
     "  --animate FPS          advance the scene's animation 1/FPS per frame (update() + "
     "render())\n"
     "  --seed N               random seed (default 1)\n"
     "  --exposure EV          stops applied before tonemapping (PNG)\n"
     "  --timings FILE.json    method, parameters, GL renderer, timer mode, per-stage times, "
     "stats\n"
     "  --no-cache             precompute afresh and keep nothing (timing of precomputation)\n"
     "  --curve-ref NAME=IMAGE record the error against IMAGE after frames 1, 2, 4, ... (up to 4)\n"
     "  --frames-out PATTERN   write every frame's linear image, PATTERN with one %d (the frame\n"
     "                         index from 0), e.g. frames/f%04d.exr (outside the timed frames)\n"
     "  --view VIEW.json       a view saved by gibench view: its camera, and its scene, method,\n"
     "                         parameters, size, frames, seed, time and exposure unless given "
     "here\n"
     "  --buffer NAME[,NAME]   write the method's debug buffers instead of the image (repeatable;\n"
     "                         gibench methods M lists them): one into each --out; several into\n"
     "                         each --out with .NAME before its extension (m.exr: m.NAME.exr)\n"
     "Prints a progress bar on a terminal and a one-line summary at the end (-q: none).\n"},
    {"reference",
     "usage: gibench reference --scene S --out FILE.exr [--out FILE.png] [options]\n"
     "Embree path-traced reference, progressive passes until a stopping rule; EXR with mean and "
     "variance.\n"
     "  --camera NAME|#k|view:FILE.json   --size WxH   --seed N   --exposure EV   --threads N\n"
     "  --spp N                 stop at N samples per pixel\n"
     "  --time S                stop after S seconds of rendering\n"
     "  --target-se E           stop when the mean relative standard error reaches E\n"
     "  --target-relmse X       stop when the reference's estimated relMSE reaches X\n"
     "  --max-bounces B|inf     path length limit (B = 1: direct light only)\n"
     "  --time-of-scene T       scene time (animation)\n"
     "  --pixel box|center      camera rays spread over the pixel (box) or through its centre\n"
     "  --stats FILE.json       samples, rays, time, standard error\n"},
    {"diff",
     "usage: gibench diff TEST REFERENCE [--json] [--heatmap FILE.png] [--flip-map FILE.png]\n"
     "                    [--exposure EV] [--ppd N] [--dark-threshold F]\n"
     "       gibench diff --black REFERENCE [options]\n"
     "Error metrics of TEST against REFERENCE: RMSE, relMSE, MAE, PSNR, SSIM, FLIP, mean "
     "luminance,\n"
     "leaked energy (TEST's light where REFERENCE is dark).\n"
     "  --json             as JSON\n"
     "  --black            score a black image of REFERENCE's size (the trivial answer) in place "
     "of TEST\n"
     "  --heatmap FILE     relative error map with its colour bar (log scale)\n"
     "  --flip-map FILE    FLIP map\n"
     "  --exposure EV      stops before tonemapping (PSNR, SSIM, FLIP)\n"
     "  --ppd N            FLIP pixels per degree (default 67.02)\n"
     "  --dark-threshold F dark pixels of the leaked energy: luminance below F x the reference's\n"
     "                     mean (default 0.01)\n"},
    {"compare",
     "usage: gibench compare --scene S --methods a,b,...|all --out DIR [options]\n"
     "Methods side by side against the path-traced references (full GI and bounce-matched);\n"
     "writes DIR/report.md, index.html and runs.csv. Options as render (--size, --frames,\n"
     "--warmup, --camera, --seed, --exposure, --time) and:\n"
     "  --param method.k=v     a parameter of one method (repeatable)\n"
     "  --reference FILE.exr   use this full-GI reference instead of rendering one\n"
     "  --ref-spp N  --ref-target-se E  --ref-bounces B   how the references are rendered\n"
     "  --timeout S            seconds per method run\n"
     "  --fresh                rerun methods even when a result for the same configuration "
     "exists\n"},
    {"study",
     "usage: gibench study STUDY.json --out DIR [--jobs N] [--resume|--fresh|--retry-failed]\n"
     "         [--mix-clocks] [--dry-run]\n"
     "         [--slurm [--partition P] [--gres G] [--time T] [--array-limit K] [--no-wait]]\n"
     "Run a declarative experiment (docs/studies.md, \"gibench study\"): every method setting x "
     "scene x repeat "
     "in\n"
     "its own process, against the references, with convergence curves, Pareto fronts and the\n"
     "equal-error and equal-time tables; cached runs are not run again.\n"
     "  --out DIR     output folder (locked while a study runs in it)\n"
     "  --jobs N      worker processes\n"
     "  --resume      keep earlier results of the same configuration (the default)\n"
     "  --fresh       run everything again (the path tracer's curve is timed again too)\n"
     "  --retry-failed  run the failed runs again (a run killed from outside, a full disk), keep "
     "the rest\n"
     "  --mix-clocks  report speed-ups whose times come from several invocations (flagged); "
     "without it\n"
     "                such a study is refused: its runs and the path tracer's curve are timed in "
     "one\n"
     "                invocation (docs/studies.md, \"One clock per comparison\")\n"
     "Exit status: 0 every run ok or n/a, 1 a run failed or the study was interrupted (the report "
     "is\n"
     "written all the same), 2 a bad study file or option.\n"
     "  --dry-run     check the file and print the plan; run nothing (with --slurm: print the job "
     "scripts)\n"
     "  --slurm       run the cells as Slurm job arrays (docs/studies.md, \"Studies on a "
     "Slurm cluster\"):\n"
     "                references, then method runs (afterok), then a collect job that writes the "
     "report\n"
     "  --partition P --gres G --time T   sbatch's options for the cells' tasks\n"
     "  --array-limit K   at most K tasks of an array at once\n"
     "  --no-wait     return once submitted (the collect job still writes the report)\n"},
    {"conformance",
     "usage: gibench conformance [--method M] [--json] [--size N] [--item-timeout S]\n"
     "The conformance suite on every method (or M): closed emitting sphere = Le * sum rho^k for "
     "its\n"
     "bounce count, finiteness, determinism, caps honesty, parameter checks.\n"
     "  --json   as JSON   --size N   image size   --item-timeout S   seconds per check\n"
     "  --held-out SEED|DIR   the held-out family of SEED (scripts/held_out.py) or of a folder it\n"
     "                        made: both furnaces, beats black and direct by 2x, converges in "
     "its\n"
     "                        quality knobs\n"
     "  --variants a,b        held-out variants to run   --no-converge   skip the knob sweeps\n"},
    {"view",
     "usage: gibench view --scene S [--method M|reference] [options]\n"
     "The interactive viewer: a window (GLFW, OpenGL 4.5 core) showing a method's image of the "
     "scene,\n"
     "through the same plugins as render, or the progressive path-traced reference.\n"
     "  --size WxH             image size (default 512x512); the window adds the panels' 340 "
     "pixels\n"
     "  --panels on|off        Dear ImGui panels right of the image (default on; off with "
     "--script)\n"
     "  --param k=v            a parameter of the starting method (repeatable)\n"
     "  --camera NAME|#k       the scene's camera to start from\n"
     "  --exposure EV  --time T  --seed N\n"
     "  --screenshot-dir DIR   where keys P (screenshot) and V (save view) write (default .)\n"
     "  --script FILE          replay key and mouse events from FILE, then exit (docs/commands.md, "
     "\"Scripts\")\n"
     "Keys: M/N next/previous method, R reference, mouse left orbit, right dolly, Ctrl+middle pan\n"
     "the camera, Ctrl+wheel dolly, wheel zoom the image about the mouse, middle drag or "
     "Ctrl+arrows\n"
     "pan the image, Z reset zoom, F1 panels, Shift+left drag move the object under the mouse,\n"
     "Ctrl+left drag rotate it, L select a light (then Shift+left drag or Shift+W/A/S/D/Q/E move "
     "it),\n"
     "W/A/S/D/Q/E fly, arrows orbit, C next scene camera, TAB/PgUp/PgDn parameters, X split view\n"
     "(reference, error, the second method chosen in the panels), O overlay (without panels), "
     "SPACE\n"
     "play/pause, ,/. time step, [/] or -/= exposure, P screenshot, V save view, ESC quit.\n"},
    {"help", "usage: gibench help [COMMAND]\nThe list of commands, or the help of one.\n"},
};

int cli_command_help(const char *cmd, FILE *to)
{
    for (size_t i = 0; i < sizeof helps / sizeof helps[0]; i++)
        if (!strcmp(helps[i].name, cmd)) {
            fputs(helps[i].text, to);
            fputs("exit status: 0 success, 1 failure while running, 2 bad usage or bad input\n",
                  to);
            return 1;
        }
    return 0;
}
