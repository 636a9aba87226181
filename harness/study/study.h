/* The study engine's entry points besides `gibench study` (cmd_study, in
 * cli.h with the other commands). */
#ifndef GIBENCH_STUDY_H
#define GIBENCH_STUDY_H

#include "cli.h"

/* The study reader alone (what --dry-run checks, without the plan): EXIT_OK,
 * or EXIT_USAGE after printing one line; for tests/fuzz/fuzz_study.c. */
int study_check(const char *file, gi_plugins *reg);
/* The same, with the study's relative paths resolved as if the study were
 * the file `as` (a fuzzer's temporary copy of a committed study). */
int study_check_as(const char *file, const char *as, gi_plugins *reg);

#endif
