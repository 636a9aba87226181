/* gibench: the command-line front door (ARCHITECTURE.md "Command line"). */
#include "cli.h"

#include "gi/log.h"

#include <stdio.h>
#include <string.h>

static const char usage[] =
    "usage: gibench [-v|-q] COMMAND ...\n"
    "commands:\n"
    "  methods [--json]                       list method plugins and their parameters\n"
    "  info SCENE [--json]                    describe a scene file\n"
    "  render --scene S --method M --out FILE [--out FILE2] [--camera C] [--size WxH]\n"
    "         [--param k=v]... [--frames N] [--warmup N] [--time T] [--animate FPS]\n"
    "         [--seed N] [--exposure EV] [--timings FILE.json] [--no-cache]\n"
    "                                         render one method (EXR, PFM or PNG output)\n"
    "  diff TEST REFERENCE [--json] [--heatmap FILE.png] [--flip-map FILE.png]\n"
    "       [--exposure EV] [--ppd N]         error metrics (RMSE, relMSE, MAE, PSNR, SSIM, FLIP)\n"
    "  compare --scene S --methods a,b,...|all --out DIR [--size WxH] [--frames N] [--warmup N]\n"
    "          [--camera C] [--reference FILE.exr] [--ref-spp N] [--ref-target-se E] [--ref-bounces B]\n"
    "          [--timeout S] [--param method.k=v]... [--seed N] [--exposure EV] [--time T] [--fresh]\n"
    "                                         methods side by side against the references\n"
    "  study STUDY.json --out DIR [--jobs N] [--resume|--fresh] [--dry-run]\n"
    "                                         run a declarative experiment and write its report\n"
    "  reference --scene S --out FILE [--out FILE2] [--camera C] [--size WxH]\n"
    "         [--spp N] [--time S] [--target-se E] [--max-bounces B|inf] [--seed N]\n"
    "         [--threads N] [--time-of-scene T] [--exposure EV] [--stats FILE.json]\n"
    "         [--pixel box|center] [--traversal fast|robust]\n"
    "                                         Embree path-traced reference (EXR: mean + variance)\n"
    "  conformance [--method M] [--json] [--size N] [--item-timeout S]\n"
    "                                         the conformance suite: every check on every method (or M)\n"
    "exit status: 0 success, 1 failure while running, 2 bad usage or bad input\n";

int main(int argc, char **argv)
{
    int i = 1;
    gi_log_set_level(GI_LOG_WARN);
    for (; i < argc && argv[i][0] == '-'; i++) {
        if (!strcmp(argv[i], "-v"))
            gi_log_set_level(GI_LOG_INFO);
        else if (!strcmp(argv[i], "-vv"))
            gi_log_set_level(GI_LOG_DEBUG);
        else if (!strcmp(argv[i], "-q"))
            gi_log_set_level(GI_LOG_ERROR);
        else if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
            fputs(usage, stdout);
            return EXIT_OK;
        } else
            return cli_fail(EXIT_USAGE, "unknown option '%s' (see gibench --help)", argv[i]);
    }
    if (i >= argc) {
        fputs(usage, stderr);
        return EXIT_USAGE;
    }
    const char *cmd = argv[i];
    int sub_argc = argc - i - 1;
    char **sub_argv = argv + i + 1;
    if (!strcmp(cmd, "methods"))
        return cmd_methods(sub_argc, sub_argv);
    if (!strcmp(cmd, "info"))
        return cmd_info(sub_argc, sub_argv);
    if (!strcmp(cmd, "render"))
        return cmd_render(sub_argc, sub_argv);
    if (!strcmp(cmd, "diff"))
        return cmd_diff(sub_argc, sub_argv);
    if (!strcmp(cmd, "compare"))
        return cmd_compare(sub_argc, sub_argv);
    if (!strcmp(cmd, "study"))
        return cmd_study(sub_argc, sub_argv);
    if (!strcmp(cmd, "reference"))
        return cmd_reference(sub_argc, sub_argv);
    if (!strcmp(cmd, "conformance"))
        return cmd_conformance(sub_argc, sub_argv);
    if (!strcmp(cmd, "help")) {
        fputs(usage, stdout);
        return EXIT_OK;
    }
    return cli_fail(EXIT_USAGE, "unknown command '%s' (see gibench --help)", cmd);
}
