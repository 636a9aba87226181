/* gibench: the command-line front door (docs/commands.md). */
#define _POSIX_C_SOURCE 200809L /* setenv */
#include "cli.h"

#include "gi/gpu.h"
#include "gi/log.h"
#include "gibench_version.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char usage[] =
    "usage: gibench [-v|-vv|-q] [--egl-device D] COMMAND ...   (gibench help COMMAND)\n"
    "       gibench --version [-v]\n"
    "  --egl-device D: auto|device|surfaceless|N|NAME, the GL device (sets GIBENCH_EGL;\n"
    "                  see docs/gpu.md)\n"
    "commands:\n"
    "  methods [--json]                       list method plugins and their parameters\n"
    "  info SCENE [--json]                    describe a scene file\n"
    "  render --scene S --method M --out FILE [--out FILE2] [--camera C] [--size WxH]\n"
    "         [--param k=v]... [--frames N] [--warmup N] [--time T] [--animate FPS]\n"
    "         [--seed N] [--exposure EV] [--timings FILE.json] [--no-cache] [--curve-ref "
    "NAME=IMG]\n"
    "         [--view VIEW.json]\n"
    "                                         render one method (EXR, PFM or PNG output)\n"
    "  view --scene S [--method M|reference] [--size WxH] [--param k=v]... [--camera C]\n"
    "       [--exposure EV] [--time T] [--seed N] [--script FILE] [--screenshot-dir DIR]\n"
    "                                         the interactive viewer (GLFW window)\n"
    "  diff TEST REFERENCE [--json] [--heatmap FILE.png] [--flip-map FILE.png]\n"
    "       [--exposure EV] [--ppd N]         error metrics (RMSE, relMSE, MAE, PSNR, SSIM, FLIP)\n"
    "  compare --scene S --methods a,b,...|all --out DIR [--size WxH] [--frames N] [--warmup N]\n"
    "          [--camera C] [--reference FILE.exr] [--ref-spp N] [--ref-target-se E] "
    "[--ref-bounces B]\n"
    "          [--timeout S] [--param method.k=v]... [--seed N] [--exposure EV] [--time T] "
    "[--fresh]\n"
    "                                         methods side by side against the references\n"
    "  study STUDY.json --out DIR [--jobs N] [--resume|--fresh] [--dry-run]\n"
    "                                         run a declarative experiment and write its report\n"
    "  reference --scene S --out FILE [--out FILE2] [--camera C] [--size WxH]\n"
    "         [--spp N] [--time S] [--target-se E] [--max-bounces B|inf] [--seed N]\n"
    "         [--threads N] [--time-of-scene T] [--exposure EV] [--stats FILE.json]\n"
    "         [--pixel box|center] [--traversal fast|robust]\n"
    "                                         Embree path-traced reference (EXR: mean + variance)\n"
    "  conformance [--method M] [--json] [--size N] [--item-timeout S]\n"
    "                                         the conformance suite: every check on every method "
    "(or M)\n"
    "exit status: 0 success, 1 failure while running, 2 bad usage or bad input\n";

/* gibench --version: the version and commit; with -v also the GL renderer
 * this machine gives (a context is made for it). */
static int print_version(void)
{
    printf("gibench %s (commit %s)\n", GIBENCH_VERSION, GIBENCH_COMMIT);
    if (gi_log_get_level() >= GI_LOG_INFO) {
        gi_error err;
        gi_gpu *gpu = gi_gpu_create(NULL, &err);
        if (!gpu)
            return cli_fail(EXIT_RUN, "no GL context: %s", err.text);
        printf("GL renderer: %s\nGL version: %s\nGL vendor: %s\nEGL platform: %s\nEGL device: "
               "%s\n",
               gi_gpu_renderer(gpu), gi_gpu_version(gpu), gi_gpu_vendor(gpu), gi_gpu_platform(gpu),
               gi_gpu_device(gpu));
        gi_gpu_destroy(gpu);
    }
    return EXIT_OK;
}

/* Is this command's help asked for ("--help" or "-h" among its arguments)? */
static int wants_help(int argc, char **argv)
{
    for (int i = 0; i < argc; i++)
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h"))
            return 1;
    return 0;
}

int main(int argc, char **argv)
{
    int i = 1, version = 0;
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
        } else if (!strcmp(argv[i], "--version"))
            version = 1;
        else if (!strcmp(argv[i], "--egl-device")) {
            /* an environment variable, so that the runs a study or compare
             * starts as child processes use the same device */
            if (i + 1 >= argc || !argv[i + 1][0])
                return cli_fail(EXIT_USAGE, "--egl-device needs a value (auto, device, "
                                            "surfaceless, a number or a name)");
            setenv("GIBENCH_EGL", argv[++i], 1);
        } else
            return cli_fail(EXIT_USAGE, "unknown option '%s' (see gibench --help)", argv[i]);
    }
    if (version)
        return i < argc ? cli_fail(EXIT_USAGE, "--version takes no command") : print_version();
    if (i >= argc) {
        fputs(usage, stderr);
        return EXIT_USAGE;
    }
    const char *cmd = argv[i];
    int sub_argc = argc - i - 1;
    char **sub_argv = argv + i + 1;
    if (!strcmp(cmd, "help")) {
        if (sub_argc == 0) {
            fputs(usage, stdout);
            return EXIT_OK;
        }
        if (sub_argc > 1)
            return cli_fail(EXIT_USAGE, "help: one command at a time (gibench help COMMAND)");
        const char *which = wants_help(1, sub_argv) ? "help" : sub_argv[0];
        if (!cli_command_help(which, stdout))
            return cli_fail(EXIT_USAGE, "help: unknown command '%s' (see gibench --help)",
                            sub_argv[0]);
        return EXIT_OK;
    }
    if (wants_help(sub_argc, sub_argv)) {
        if (!cli_command_help(cmd, stdout))
            return cli_fail(EXIT_USAGE, "unknown command '%s' (see gibench --help)", cmd);
        return EXIT_OK;
    }
    /* every command times or passes the mode to its children */
    gi_error terr;
    if (gi_timer_env_check(&terr) != GI_OK)
        return cli_fail(EXIT_USAGE, "%s", terr.text);
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
    if (!strcmp(cmd, "view"))
        return cmd_view(sub_argc, sub_argv);
    return cli_fail(EXIT_USAGE, "unknown command '%s' (see gibench --help)", cmd);
}
