/* The floor of a warm sandbox's match: what the kernel must do to give one match a world
 * of its own with the walls of mazearena's warm sandbox, and nothing else: no runner, no
 * supervisor's messages, no cgroup bookkeeping, no JSON. Each round starts a program
 * (BOT, run in its folder) and waits for it, either
 *   plain      posix_spawn, as a runner without a sandbox starts a bot; or
 *   isolated   a clone into new PID, mount and IPC namespaces whose first process
 *              makes the mounts private, mounts a fresh /proc (with the parts the
 *              sandbox keeps read-only bound read-only) and a scratch tmpfs (with
 *              tmp/ and work/), binds the bot's folder read-only, links the folder's
 *              entries into work/, and puts up the walls (limits, an unprivileged uid, no
 *              new privileges, Landlock, a seccomp deny list of the same length as the
 *              warm sandbox's per-match one), then starts BOT with posix_spawn, waits for
 *              it and ends, taking its namespaces with it; or
 *   isolated-net the same in a network namespace of its own too, its loopback brought
 *              up (as every warm match has since each got one).
 * It prints, for ROUNDS rounds, the wall time and the machine's CPU time (/proc/stat:
 * the kernel's work on other cores, such as a namespace's tear-down, included) per
 * round.
 *
 *   warm_floor plain|isolated|isolated-net ROUNDS WORK BOTDIR BOT [ARGS...]
 *
 * WORK is an empty folder of the caller's (the scratch mount point and the bot's
 * folder's mount point are made in it). Needs root. */
#define _GNU_SOURCE
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <linux/filter.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <linux/seccomp.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <grp.h>
#include <sys/mount.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

extern char **environ;

static void die(const char *what) { perror(what); _exit(1); }

static long long busy_ticks(void) {
    FILE *f = fopen("/proc/stat", "r");
    long long v[8] = {0};
    if (!f || fscanf(f, "cpu %lld %lld %lld %lld %lld %lld %lld %lld", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6], &v[7]) != 8) die("/proc/stat");
    fclose(f);
    return v[0] + v[1] + v[2] + v[5] + v[6];
}

static pid_t spawn_bot(char **bot) {
    pid_t pid;
    if (posix_spawn(&pid, bot[0], NULL, NULL, bot, environ) != 0) die("posix_spawn");
    return pid;
}

/* Landlock by its system calls (the headers of older systems lack the newer fields). */
static void landlock(const char *scratch) {
    struct { unsigned long long fs, net, scoped; } attr = {(1ULL << 16) - 1, 3, 3};
    int ruleset = syscall(SYS_landlock_create_ruleset, &attr, sizeof attr, 0);
    if (ruleset < 0) return; /* a kernel without Landlock: best effort, as mazearena */
    const char *paths[] = {"/", "/dev", scratch};
    unsigned long long access[] = {(1ULL << 0) | (1ULL << 2) | (1ULL << 3), (1ULL << 0) | (1ULL << 1) | (1ULL << 2) | (1ULL << 3), (1ULL << 16) - 1};
    for (int i = 0; i < 3; i++) {
        struct __attribute__((packed)) { unsigned long long allowed; int parent; } rule = {access[i], open(paths[i], O_PATH | O_CLOEXEC)};
        if (rule.parent < 0 || syscall(SYS_landlock_add_rule, ruleset, 1, &rule, 0) != 0) die("landlock_add_rule");
        close(rule.parent);
    }
    if (syscall(SYS_landlock_restrict_self, ruleset, 0) != 0) die("landlock_restrict_self");
    close(ruleset);
}

/* A deny list as long as the warm sandbox's per-match filter: 13 calls, clone's 7
 * namespace flags, then the x32 ABI and clone3. */
static void seccomp(void) {
    static const int denied[] = {165, 166, 155, 161, 428, 429, 430, 431, 432, 433, 442, 272, 308};
    static const unsigned flags[] = {CLONE_NEWUSER, CLONE_NEWNS, CLONE_NEWPID, CLONE_NEWNET, CLONE_NEWIPC, CLONE_NEWUTS, CLONE_NEWCGROUP};
    struct sock_filter f[64];
    int n = 0;
    f[n++] = (struct sock_filter)BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(struct seccomp_data, arch));
    f[n++] = (struct sock_filter)BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, 0xC000003E, 1, 0);
    f[n++] = (struct sock_filter)BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_KILL_PROCESS);
    f[n++] = (struct sock_filter)BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(struct seccomp_data, nr));
    f[n++] = (struct sock_filter)BPF_JUMP(BPF_JMP | BPF_JGE | BPF_K, 0x40000000, 0, 1);
    f[n++] = (struct sock_filter)BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | EPERM);
    f[n++] = (struct sock_filter)BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, 435, 0, 1);
    f[n++] = (struct sock_filter)BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | ENOSYS);
    for (int i = 0; i < 13; i++) {
        f[n++] = (struct sock_filter)BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, denied[i], 0, 1);
        f[n++] = (struct sock_filter)BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | EPERM);
    }
    f[n++] = (struct sock_filter)BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, 56, 1, 0);
    f[n++] = (struct sock_filter)BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW);
    f[n++] = (struct sock_filter)BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(struct seccomp_data, args[0]));
    for (int i = 0; i < 7; i++) {
        f[n++] = (struct sock_filter)BPF_JUMP(BPF_JMP | BPF_JSET | BPF_K, flags[i], 0, 1);
        f[n++] = (struct sock_filter)BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | EPERM);
    }
    f[n++] = (struct sock_filter)BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW);
    struct sock_fprog prog = {.len = (unsigned short)n, .filter = f};
    if (prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &prog) != 0) die("seccomp");
}

/* Brings the loopback of this process's network namespace up. */
static void loopback_up(void) {
    int s = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    struct ifreq req;
    memset(&req, 0, sizeof req);
    strcpy(req.ifr_name, "lo");
    if (s < 0 || ioctl(s, SIOCGIFFLAGS, &req)) die("lo");
    req.ifr_flags |= IFF_UP;
    if (ioctl(s, SIOCSIFFLAGS, &req)) die("lo up");
    close(s);
}

static int match_init(const char *work, const char *botdir, char **bot, int net) {
    char scratch[4096], mounted[4096], path[8192], target[8192];
    if (net) loopback_up();
    snprintf(scratch, sizeof scratch, "%s/scratch", work);
    snprintf(mounted, sizeof mounted, "%s/bot", work);
    if (mount(NULL, "/", NULL, MS_REC | MS_PRIVATE, NULL)) die("private");
    if (mount("proc", "/proc", "proc", MS_NOSUID | MS_NODEV | MS_NOEXEC, NULL)) die("proc");
    /* The parts of /proc the sandbox keeps read-only. */
    static const char *ro[] = {"/proc/sys", "/proc/sysrq-trigger", "/proc/irq", "/proc/bus"};
    for (int i = 0; i < 4; i++) {
        if (access(ro[i], F_OK) != 0) continue;
        if (mount(ro[i], ro[i], NULL, MS_BIND | MS_REC, NULL)) die(ro[i]);
        if (mount(NULL, ro[i], NULL, MS_BIND | MS_REMOUNT | MS_RDONLY | MS_NOSUID | MS_NODEV | MS_NOEXEC, NULL)) die(ro[i]);
    }
    if (mount("tmpfs", scratch, "tmpfs", MS_NOSUID | MS_NODEV, "size=67108864,mode=0755")) die("tmpfs");
    if (mount(botdir, mounted, NULL, MS_BIND | MS_REC, NULL)) die("bind");
    if (mount(NULL, mounted, NULL, MS_BIND | MS_REMOUNT | MS_RDONLY, NULL)) die("remount");
    snprintf(path, sizeof path, "%s/tmp", scratch);
    if (mkdir(path, 01777) || chmod(path, 01777)) die("tmp");
    snprintf(path, sizeof path, "%s/work", scratch);
    if (mkdir(path, 0777) || chmod(path, 0777)) die("work");
    if (chdir(path)) die("chdir");
    struct rlimit core = {0, 0}, fsize = {1 << 26, 1 << 26}, nproc = {68, 68};
    setrlimit(RLIMIT_CORE, &core);
    setrlimit(RLIMIT_FSIZE, &fsize);
    if (setgroups(0, NULL) || setresgid(2000000000, 2000000000, 2000000000) || setresuid(2000000000, 2000000000, 2000000000)) die("uid");
    setrlimit(RLIMIT_NPROC, &nproc);
    if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0)) die("no_new_privs");
    landlock(scratch);
    seccomp();
    DIR *d = opendir(mounted);
    if (!d) die("opendir");
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        snprintf(target, sizeof target, "%s/%s", mounted, e->d_name);
        if (symlink(target, e->d_name)) die("symlink");
    }
    closedir(d);
    pid_t bot_pid = spawn_bot(bot);
    int status;
    for (;;) {
        pid_t got = waitpid(-1, &status, 0);
        if (got == bot_pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
        if (got < 0 && errno != EINTR) return 1;
    }
}

int main(int argc, char **argv) {
    if (argc < 6) { fprintf(stderr, "usage: warm_floor plain|isolated|isolated-net ROUNDS WORK BOTDIR BOT [ARGS...]\n"); return 2; }
    int net = strcmp(argv[1], "isolated-net") == 0;
    int isolated = net || strcmp(argv[1], "isolated") == 0;
    int rounds = atoi(argv[2]);
    const char *work = argv[3], *botdir = argv[4];
    char **bot = argv + 5;
    char path[4096];
    snprintf(path, sizeof path, "%s/scratch", work);
    mkdir(path, 0755);
    snprintf(path, sizeof path, "%s/bot", work);
    mkdir(path, 0755);
    if (chdir(botdir)) die(botdir);
    long long busy0 = busy_ticks();
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    for (int i = 0; i < rounds; i++) {
        pid_t pid;
        if (isolated) {
            int flags = CLONE_NEWPID | CLONE_NEWNS | CLONE_NEWIPC | (net ? CLONE_NEWNET : 0);
            pid = syscall(SYS_clone, flags | SIGCHLD, 0, 0, 0, 0);
            if (pid < 0) die("clone");
            if (pid == 0) _exit(match_init(work, botdir, bot, net));
        } else {
            pid = spawn_bot(bot);
        }
        int status;
        if (waitpid(pid, &status, 0) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
            fprintf(stderr, "warm_floor: round %d failed (status %d)\n", i, status);
            return 1;
        }
    }
    clock_gettime(CLOCK_MONOTONIC, &b);
    /* The namespaces' tear-down finishes on other cores after the last round: a moment. */
    usleep(200000);
    long long busy = busy_ticks() - busy0;
    double wall_ms = ((b.tv_sec - a.tv_sec) * 1e3 + (b.tv_nsec - a.tv_nsec) / 1e6) / rounds;
    double cpu_ms = busy * 1000.0 / sysconf(_SC_CLK_TCK) / rounds;
    printf("%.3f %.3f\n", wall_ms, cpu_ms);
    return 0;
}
