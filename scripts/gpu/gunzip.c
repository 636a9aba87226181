/* gi-gunzip IN.gz OUT: the bundle's own gunzip (scripts/gpu/bundle.sh).
 *
 * Embree is most of the bundle's size; it travels gzipped and the launcher
 * unpacks it once on the node. A GPU node may have no gzip, so the bundle
 * brings this helper, linked with a static zlib and needing only libc.
 * OUT is written under a temporary name and renamed, so an interrupted
 * unpack never leaves a truncated library behind. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: gi-gunzip IN.gz OUT\n");
        return 2;
    }
    gzFile in = gzopen(argv[1], "rb");
    if (!in) {
        fprintf(stderr, "gi-gunzip: cannot open %s\n", argv[1]);
        return 1;
    }
    char tmp[4096];
    snprintf(tmp, sizeof tmp, "%s.part.%ld", argv[2], (long)getpid());
    FILE *out = fopen(tmp, "wb");
    if (!out) {
        fprintf(stderr, "gi-gunzip: cannot write %s\n", tmp);
        gzclose(in);
        return 1;
    }
    static char buf[1 << 16];
    int n, ok = 1;
    while ((n = gzread(in, buf, sizeof buf)) > 0)
        if (fwrite(buf, 1, (size_t)n, out) != (size_t)n) {
            ok = 0;
            break;
        }
    if (n < 0)
        ok = 0;
    gzclose(in);
    if (fclose(out) != 0)
        ok = 0;
    if (!ok || rename(tmp, argv[2]) != 0) {
        fprintf(stderr, "gi-gunzip: %s -> %s failed\n", argv[1], argv[2]);
        unlink(tmp);
        return 1;
    }
    return 0;
}
