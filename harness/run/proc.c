/* Child processes with a time limit (proc.h). */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE
#include "proc.h"

#include "cli.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif
#include <time.h>
#include <unistd.h>

const char *cli_self_exe(void)
{
    static char path[4096];
    if (!path[0]) {
        ssize_t n = readlink("/proc/self/exe", path, sizeof path - 1);
        path[n > 0 ? n : 0] = '\0';
    }
    return path;
}

static void read_last_line(const char *log_path, char *out, size_t size)
{
    out[0] = '\0';
    if (!log_path)
        return;
    FILE *f = fopen(log_path, "rb");
    if (!f)
        return;
    /* Only the tail matters: read the last 4 KiB. */
    char buf[4096];
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    long start = len > (long)sizeof buf - 1 ? len - (long)sizeof buf + 1 : 0;
    fseek(f, start, SEEK_SET);
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    /* strip progress-bar carriage returns and trailing blank lines */
    for (size_t i = 0; i < n; i++)
        if (buf[i] == '\r')
            buf[i] = '\n';
    while (n > 0 && (buf[n - 1] == '\n' || buf[n - 1] == ' '))
        buf[--n] = '\0';
    const char *last = strrchr(buf, '\n');
    last = last ? last + 1 : buf;
    size_t keep = strlen(last);
    keep = keep < size - 1 ? keep : size - 1;
    memcpy(out, last, keep);
    out[keep] = '\0';
}

int cli_run(char *const argv[], double timeout_s, const char *out_path, const char *err_path,
            cli_proc_result *r)
{
    memset(r, 0, sizeof *r);
    if (cli_interrupted) { /* nothing new starts once gibench is interrupted */
        r->interrupted = 1;
        r->exit_code = -1; /* not done: no caller may read it as success */
        snprintf(r->last_line, sizeof r->last_line, "not started: interrupted");
        return 0;
    }
    double t0 = gi_now();
    pid_t parent = getpid();
    pid_t pid = fork();
    if (pid < 0) {
        snprintf(r->last_line, sizeof r->last_line, "fork failed: %s", strerror(errno));
        return -1;
    }
    if (pid == 0) {
        setpgid(0, 0); /* so that a time-out kills the child's children too */
#ifdef __linux__
        /* gibench killed outright (SIGKILL) takes its child along */
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (getppid() != parent)
            _exit(127);
#else
        (void)parent;
#endif
        int fo = open(out_path ? out_path : "/dev/null", O_WRONLY | O_CREAT | O_TRUNC, 0644);
        int fe = err_path && out_path && !strcmp(err_path, out_path)
                     ? dup(fo)
                     : open(err_path ? err_path : "/dev/null", O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fo >= 0) {
            dup2(fo, STDOUT_FILENO);
            close(fo);
        }
        if (fe >= 0) {
            dup2(fe, STDERR_FILENO);
            close(fe);
        }
        int devnull = open("/dev/null", O_RDONLY);
        if (devnull >= 0) {
            dup2(devnull, STDIN_FILENO);
            close(devnull);
        }
        execv(argv[0], argv);
        fprintf(stderr, "gibench: cannot run %s: %s\n", argv[0], strerror(errno));
        _exit(127);
    }
    setpgid(pid, pid);
    int status = 0;
    double term_sent = 0.0;
    for (;;) {
        pid_t w = waitpid(pid, &status, WNOHANG);
        if (w == pid)
            break;
        if (w < 0 && errno != EINTR) {
            snprintf(r->last_line, sizeof r->last_line, "waitpid failed: %s", strerror(errno));
            return -1;
        }
        if (timeout_s > 0 && gi_now() - t0 > timeout_s) {
            kill(-pid, SIGKILL);
            waitpid(pid, &status, 0);
            r->timed_out = 1;
            break;
        }
        if (cli_interrupted) {
            /* SIGTERM to the whole group, SIGKILL after the grace period */
            if (!term_sent) {
                kill(-pid, SIGTERM);
                term_sent = gi_now();
            } else if (gi_now() - term_sent > CLI_KILL_GRACE_S) {
                kill(-pid, SIGKILL);
            }
        }
        struct timespec ts = {0, 5 * 1000 * 1000};
        nanosleep(&ts, NULL);
    }
    r->seconds = gi_now() - t0;
    if (term_sent > 0.0 && !r->timed_out && !(WIFEXITED(status) && WEXITSTATUS(status) == 0)) {
        kill(-pid, SIGKILL); /* whatever of the group is left */
        r->interrupted = 1;
        /* the child's own status (never 0 here), so that a caller reading
         * exit_code alone cannot take the unfinished work as done */
        r->exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    } else if (!r->timed_out) {
        if (WIFSIGNALED(status)) {
            r->signaled = 1;
            r->signal = WTERMSIG(status);
        } else {
            r->exit_code = WEXITSTATUS(status);
        }
    }
    read_last_line(err_path, r->last_line, sizeof r->last_line);
    return 0;
}

int cli_proc_ok(const cli_proc_result *r)
{
    return !r->interrupted && !r->timed_out && !r->signaled && r->exit_code == 0;
}

int cli_reason_external(const char *reason)
{
    static const char *const marks[] = {"killed (signal", "(signal 9:", "No space left on device",
                                        "Disk quota exceeded", "Input/output error"};
    for (size_t i = 0; reason && i < sizeof marks / sizeof marks[0]; i++)
        if (strstr(reason, marks[i]))
            return 1;
    return 0;
}

void cli_proc_describe(const cli_proc_result *r, char *buf, size_t size)
{
    if (r->interrupted)
        snprintf(buf, size, "interrupted");
    else if (r->timed_out)
        snprintf(buf, size, "timed out after %.0f s", r->seconds);
    else if (r->signaled)
        /* SIGKILL, SIGTERM and SIGHUP come from outside (the out-of-memory
         * killer, an administrator, a scheduler), not from the method */
        snprintf(buf, size, "%s (signal %d: %s)%s%s",
                 r->signal == SIGKILL || r->signal == SIGTERM || r->signal == SIGHUP ? "killed"
                                                                                     : "crashed",
                 r->signal, strsignal(r->signal), r->last_line[0] ? ": " : "", r->last_line);
    else if (r->exit_code != 0)
        snprintf(buf, size, "exit %d%s%s", r->exit_code, r->last_line[0] ? ": " : "", r->last_line);
    else
        snprintf(buf, size, "ok");
}
