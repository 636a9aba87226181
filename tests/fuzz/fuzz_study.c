/* libFuzzer target for the study reader (gibench study's --dry-run checks):
 * any bytes must be taken or refused with one line, never crash, leak,
 * hang or trip a sanitizer. The bytes are written to a temporary regular
 * file (the reader opens only those) and read by study_check_as() against the
 * plugins of GIBENCH_PLUGIN_DIR and $GIBENCH_PLUGIN_PATH, loaded once.
 * Relative scene paths resolve as if the study lay in harness/studies/ of
 * the source tree (GI_FUZZ_ROOT), where the seeds' "base" keys expect it. The reader's one-line
 * refusals go to stderr: run with -close_fd_mask=2 to hide them. */
#define _POSIX_C_SOURCE 200809L
#include "study.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static gi_plugins *registry;
static char study_path[64];

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc, (void)argv;
    if (chdir(GI_FUZZ_ROOT) != 0) {
        perror(GI_FUZZ_ROOT);
        exit(1);
    }
    registry = gi_plugins_scan(GIBENCH_PLUGIN_DIR);
    snprintf(study_path, sizeof study_path, "/tmp/gibench_fuzz_study_%ld.json", (long)getpid());
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    FILE *f = fopen(study_path, "wb");
    if (!f)
        return 0;
    size_t written = size ? fwrite(data, 1, size, f) : 0;
    if (fclose(f) != 0 || written != size)
        return 0;
    (void)study_check_as(study_path, "harness/studies/fuzz.json", registry);
    return 0;
}
