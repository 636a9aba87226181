/* Child processes with a time limit: every method run of `compare` and
 * `study` happens in its own process, so a crash or a hang costs that run
 * alone. */
#ifndef GIBENCH_PROC_H
#define GIBENCH_PROC_H

#include <stddef.h>

typedef struct cli_proc_result {
    int exit_code; /* valid when !signaled && !timed_out; never 0 when interrupted */
    int signaled;  /* killed by a signal (crash) */
    int signal;
    int timed_out;       /* killed by us at the time limit */
    int interrupted;     /* stopped (or never started) because gibench was interrupted */
    double seconds;      /* wall time */
    char last_line[512]; /* last non-empty line the child printed (stderr + stdout) */
} cli_proc_result;

/* Seconds between the SIGTERM that an interrupted gibench sends to a
 * child's process group and the SIGKILL that follows when it is still there. */
#define CLI_KILL_GRACE_S 5.0

/* Runs argv (argv[0] a path) with stdout written to out_path and stderr to
 * err_path (either may be NULL: discarded; the same path for both merges
 * them), killing its whole process group after timeout_s seconds (<= 0: no
 * limit). Returns 0 when the child could be started, -1 otherwise
 * (result->last_line says why). last_line is taken from err_path. */
int cli_run(char *const argv[], double timeout_s, const char *out_path, const char *err_path,
            cli_proc_result *result);

/* When gibench itself is interrupted (SIGINT/SIGTERM: cli_interrupted), a
 * child not yet started is not started, and a running child's process group
 * gets SIGTERM, then SIGKILL after CLI_KILL_GRACE_S; unless it still exits 0,
 * the result says interrupted (a run to redo, not a failed one). A child
 * also gets SIGKILL when gibench dies (PR_SET_PDEATHSIG, Linux).
 *
 * One-line description of how a run ended: "ok", "exit 2: <line>",
 * "crashed (signal 11: Segmentation fault): <line>", "killed (signal 9: Killed)",
 * "timed out after 30 s",
 * "interrupted". */
void cli_proc_describe(const cli_proc_result *r, char *buf, size_t size);

/* 1 when the child ran to its end and exited 0: started, not interrupted,
 * not timed out, not killed. Every caller of a child asks this, never
 * exit_code alone: an interrupted child has not done its work, whatever
 * its status. */
int cli_proc_ok(const cli_proc_result *r);

/* 1 when a failure, as cli_proc_describe words it (a run record's
 * "reason"), looks external, not the method's own: the child was killed by
 * a signal it does not raise itself (SIGKILL, as the out-of-memory killer
 * sends, SIGTERM or SIGHUP from outside: "killed (signal 9: ...)"), or its
 * last line reports a full disk, a quota or an I/O error (ENOSPC, EDQUOT,
 * EIO). Such a run may well succeed when retried (study --retry-failed). */
int cli_reason_external(const char *reason);

/* Absolute path of the running gibench executable. */
const char *cli_self_exe(void);

#endif
