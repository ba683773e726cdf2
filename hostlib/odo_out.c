/// odo_out: see odo_out.h for the rule. Implementation notes:
///  - Every temp path (file or folder, and every parent folder created) is registered in one list
///    before it is created and unregistered when it is committed or removed. The list is changed
///    with the cleanup signals blocked, so the handler always walks a whole list; newest first, so
///    files go before their folders.
///  - Identity checks use (st_dev, st_ino), which sees through symlinks, bind mounts and "..".
#include "odo_out.h"
#include "odo_err.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* ---------------------------------------------------------------------------------------------
 * Cleanup registry
 * ------------------------------------------------------------------------------------------- */

typedef struct reg_node {
    struct reg_node *next;
    int is_dir;
    char path[];
} reg_node_t;

static reg_node_t *volatile g_reg = NULL;
static int g_installed = 0;

static const int k_signals[] = {SIGINT, SIGTERM, SIGHUP, SIGABRT};

/// Declared weak so the library links with and without the sanitizer runtime.
extern void __sanitizer_set_death_callback(void (*callback)(void)) __attribute__((weak));

void odo_out_cleanup_now(void)
{
    for (reg_node_t *n = g_reg; n != NULL; n = n->next) {
        if (n->is_dir) {
            (void)rmdir(n->path);
        } else {
            (void)unlink(n->path);
        }
    }
}

static void on_signal(int sig)
{
    odo_out_cleanup_now();
    (void)signal(sig, SIG_DFL);
    (void)raise(sig);
}

static void at_exit(void) { odo_out_cleanup_now(); }

/// Called whenever a temp is registered: a signal whose action is still the default gets our
/// handler (a tool with its own, e.g. odo-replay's SIGINT = stop and save, keeps it).
static void install(void)
{
    for (size_t i = 0; i < sizeof k_signals / sizeof k_signals[0]; ++i) {
        struct sigaction old;
        if (sigaction(k_signals[i], NULL, &old) == 0 && old.sa_handler == SIG_DFL) {
            struct sigaction sa;
            memset(&sa, 0, sizeof sa);
            sa.sa_handler = on_signal;
            sigemptyset(&sa.sa_mask);
            (void)sigaction(k_signals[i], &sa, NULL);
        }
    }
    if (!g_installed) {
        g_installed = 1;
        (void)atexit(at_exit);
        if (__sanitizer_set_death_callback != NULL) {
            __sanitizer_set_death_callback(at_exit);
        }
    }
}

static void block(sigset_t *old)
{
    sigset_t s;
    sigemptyset(&s);
    for (size_t i = 0; i < sizeof k_signals / sizeof k_signals[0]; ++i) {
        sigaddset(&s, k_signals[i]);
    }
    (void)sigprocmask(SIG_BLOCK, &s, old);
}

static void unblock(const sigset_t *old) { (void)sigprocmask(SIG_SETMASK, old, NULL); }

static reg_node_t *reg_add(const char *path, int is_dir)
{
    install();
    const size_t len = strlen(path) + 1U;
    reg_node_t *n = malloc(sizeof *n + len);
    if (n == NULL) {
        return NULL;
    }
    n->is_dir = is_dir;
    memcpy(n->path, path, len);
    sigset_t old;
    block(&old);
    n->next = g_reg;
    g_reg = n;
    unblock(&old);
    return n;
}

static void reg_drop(reg_node_t *n)
{
    if (n == NULL) {
        return;
    }
    sigset_t old;
    block(&old);
    for (reg_node_t *volatile *p = &g_reg; *p != NULL; p = &(*p)->next) {
        if (*p == n) {
            *p = n->next;
            break;
        }
    }
    unblock(&old);
    free(n);
}

/* ---------------------------------------------------------------------------------------------
 * Small helpers
 * ------------------------------------------------------------------------------------------- */

static const char *kind_of(mode_t m)
{
    return S_ISREG(m)    ? "a file"
           : S_ISDIR(m)  ? "a folder"
           : S_ISLNK(m)  ? "a symbolic link"
           : S_ISFIFO(m) ? "a FIFO"
           : S_ISCHR(m)  ? "a character device"
           : S_ISBLK(m)  ? "a block device"
           : S_ISSOCK(m) ? "a socket"
                         : "not a regular file";
}

static int join(char *dst, size_t n, const char *a, const char *b)
{
    const size_t la = strlen(a), lb = strlen(b);
    if (la + lb + 2U > n) {
        return -1;
    }
    memcpy(dst, a, la);
    dst[la] = '/';
    memcpy(dst + la + 1U, b, lb + 1U);
    return 0;
}

/// dirname and basename of path into caller buffers; "" dir means ".".
static int split(const char *path, char *dir, char *base)
{
    const size_t len = strlen(path);
    if (len == 0U || len >= PATH_MAX) {
        return -1;
    }
    char p[PATH_MAX];
    memcpy(p, path, len + 1U);
    size_t end = len;
    while (end > 1U && p[end - 1U] == '/') {
        p[--end] = '\0';
    }
    char *slash = strrchr(p, '/');
    if (slash == NULL) {
        strcpy(dir, ".");
        strcpy(base, p);
    } else if (slash == p) {
        strcpy(dir, "/");
        strcpy(base, slash + 1);
    } else {
        *slash = '\0';
        strcpy(dir, p);
        strcpy(base, slash + 1);
    }
    if (base[0] == '\0' || strcmp(base, ".") == 0 || strcmp(base, "..") == 0) {
        return -1;
    }
    return 0;
}

static unsigned long g_test_seed = 0;

void odo_out_test_temp_names(unsigned long seed) { g_test_seed = seed; }

/// A fresh suffix for temp names: pid, time and a counter (collisions are retried anyway).
static unsigned long next_suffix(void)
{
    static unsigned long counter = 0;
    if (g_test_seed != 0UL) {
        return g_test_seed++ & 0xFFFFFFUL;
    }
    struct timespec ts;
    (void)clock_gettime(CLOCK_MONOTONIC, &ts);
    counter++;
    return ((unsigned long)ts.tv_nsec ^ (counter * 2654435761UL)) & 0xFFFFFFUL;
}

static mode_t current_umask(void)
{
    const mode_t m = umask(022);
    (void)umask(m);
    return m;
}

typedef struct parents {
    size_t n;
    reg_node_t *node[64];
} parents_t;

/// mkdir -p of dir; each folder made is registered (removed again if the run fails).
static int make_parents(const char *dir, parents_t *made, char *err, size_t errlen)
{
    char p[PATH_MAX];
    const size_t len = strlen(dir);
    if (len >= sizeof p) {
        return odo_errf(err, errlen, "%s: path too long", dir);
    }
    memcpy(p, dir, len + 1U);
    for (size_t i = 1; i <= len; ++i) {
        if (p[i] != '/' && p[i] != '\0') {
            continue;
        }
        const char keep = p[i];
        p[i] = '\0';
        struct stat sb;
        if (stat(p, &sb) != 0) {
            if (errno != ENOENT) {
                return odo_errf(err, errlen, "%s: %s", p, strerror(errno));
            }
            reg_node_t *n = (made->n < sizeof made->node / sizeof made->node[0]) ? reg_add(p, 1) : NULL;
            if (n == NULL) {
                return odo_errf(err, errlen, "%s: too many folders to create", dir);
            }
            if (mkdir(p, 0777) != 0) {
                const int e = errno;
                reg_drop(n);
                return odo_errf(err, errlen, "cannot create folder %s: %s", p, strerror(e));
            }
            made->node[made->n++] = n;
        } else if (!S_ISDIR(sb.st_mode)) {
            return odo_errf(err, errlen, "%s is not a folder", p);
        }
        p[i] = keep;
    }
    return 0;
}

static void parents_undo(parents_t *made)
{
    if (made == NULL) {
        return;
    }
    while (made->n > 0U) {
        reg_node_t *n = made->node[--made->n];
        (void)rmdir(n->path);
        reg_drop(n);
    }
}

static void parents_keep(parents_t *made)
{
    if (made == NULL) {
        return;
    }
    while (made->n > 0U) {
        reg_drop(made->node[--made->n]);
    }
}

/* ODO_OUT_NO_FSYNC: the fuzz build only (fuzz/CMakeLists.txt), where durability is not what is
 * tested and a disk shared with other jobs makes every fsync cost tens of milliseconds. */
#ifdef ODO_OUT_NO_FSYNC
#define fsync(fd) ((void)(fd), 0)
#endif

static void fsync_dir(const char *dir)
{
    const int fd = open(dir, O_RDONLY | O_DIRECTORY);
    if (fd >= 0) {
        (void)fsync(fd);
        (void)close(fd);
    }
}

/* ---------------------------------------------------------------------------------------------
 * Inputs
 * ------------------------------------------------------------------------------------------- */

void odo_out_inputs_init(odo_out_inputs_t *ins) { ins->n = 0U; }

int odo_out_inputs_add(odo_out_inputs_t *ins, const char *path, char *err, size_t errlen)
{
    struct stat sb;
    if (path == NULL || stat(path, &sb) != 0) {
        return 0;
    }
    if (ins->n >= sizeof ins->in / sizeof ins->in[0]) {
        return odo_errf(err, errlen, "too many inputs");
    }
    ins->in[ins->n].dev = sb.st_dev;
    ins->in[ins->n].ino = sb.st_ino;
    ins->in[ins->n].is_dir = S_ISDIR(sb.st_mode);
    (void)snprintf(ins->in[ins->n].path, sizeof ins->in[ins->n].path, "%s", path);
    ins->n++;
    return 0;
}

static const char *input_match(const odo_out_inputs_t *ins, const struct stat *sb, bool dirs_only)
{
    for (size_t i = 0; ins != NULL && i < ins->n; ++i) {
        if (ins->in[i].dev == sb->st_dev && ins->in[i].ino == sb->st_ino && (!dirs_only || ins->in[i].is_dir)) {
            return ins->in[i].path;
        }
    }
    return NULL;
}

int odo_out_check_inputs(const odo_out_inputs_t *ins, const char *path, char *err, size_t errlen)
{
    if (ins == NULL || ins->n == 0U) {
        return 0;
    }
    struct stat sb;
    const char *hit;
    if (stat(path, &sb) == 0 && (hit = input_match(ins, &sb, false)) != NULL) {
        return odo_errf(err, errlen, "%s: the output is also an input (%s); refusing to overwrite it", path, hit);
    }
    /* Every existing ancestor, by identity: "a/../b", symlinked folders and bind mounts included. */
    char p[PATH_MAX];
    if (snprintf(p, sizeof p, "%s", path) >= (int)sizeof p) {
        return odo_errf(err, errlen, "%s: path too long", path);
    }
    for (;;) {
        char dir[PATH_MAX], base[PATH_MAX];
        if (split(p, dir, base) != 0) {
            break;
        }
        if (stat(dir, &sb) == 0 && (hit = input_match(ins, &sb, true)) != NULL) {
            return odo_errf(err, errlen, "%s: the output lies inside the input folder %s; refusing to write there",
                            path, hit);
        }
        if (strcmp(dir, ".") == 0 || strcmp(dir, "/") == 0) {
            break;
        }
        memcpy(p, dir, strlen(dir) + 1U);
    }
    /* A relative path's ancestors beyond "." are the working folder's. */
    if (path[0] != '/') {
        char cwd[PATH_MAX];
        if (getcwd(cwd, sizeof cwd) != NULL) {
            for (;;) {
                if (stat(cwd, &sb) == 0 && (hit = input_match(ins, &sb, true)) != NULL) {
                    return odo_errf(err, errlen,
                                    "%s: the output lies inside the input folder %s; refusing to write there", path,
                                    hit);
                }
                char *slash = strrchr(cwd, '/');
                if (slash == NULL || slash == cwd) {
                    break;
                }
                *slash = '\0';
            }
        }
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------------
 * Files
 * ------------------------------------------------------------------------------------------- */

/// Open a fresh temp in dir for base: O_CREAT|O_EXCL|O_NOFOLLOW, retried on EEXIST.
static int open_temp(const char *dir, const char *base, char *tmp, reg_node_t **reg, char *err, size_t errlen)
{
    for (int attempt = 0; attempt < 100; ++attempt) {
        const int w = snprintf(tmp, PATH_MAX, "%s/.%s.tmp-%ld-%06lx", dir, base, (long)getpid(), next_suffix());
        if (w < 0 || w >= PATH_MAX) {
            return odo_errf(err, errlen, "%s/%s: path too long", dir, base);
        }
        reg_node_t *n = reg_add(tmp, 0);
        if (n == NULL) {
            return odo_errf(err, errlen, "out of memory");
        }
        const int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
        if (fd >= 0) {
            *reg = n;
            return fd;
        }
        const int e = errno;
        reg_drop(n); /* not ours: never unlink what another process (or a planted link) holds */
        if (e != EEXIST) {
            return odo_errf(err, errlen, "cannot create a temp file in %s: %s", dir, strerror(e));
        }
    }
    return odo_errf(err, errlen, "cannot create a temp file in %s: every name taken", dir);
}

/// The target may be absent or a regular file (not through a symlink).
static int check_file_target(const char *path, char *err, size_t errlen)
{
    struct stat sb;
    if (lstat(path, &sb) != 0) {
        /* ENOTDIR: an ancestor is not a folder; make_parents names it. */
        return (errno == ENOENT || errno == ENOTDIR) ? 0 : odo_errf(err, errlen, "%s: %s", path, strerror(errno));
    }
    if (!S_ISREG(sb.st_mode)) {
        return odo_errf(err, errlen, "%s is %s, not a regular file; refusing to replace it", path, kind_of(sb.st_mode));
    }
    return 0;
}

int odo_out_file_begin(odo_out_file_t *o, const char *path, const odo_out_inputs_t *ins, char *err, size_t errlen)
{
    memset(o, 0, sizeof *o);
    char dir[PATH_MAX], base[PATH_MAX];
    if (path == NULL || split(path, dir, base) != 0) {
        return odo_errf(err, errlen, "'%s' is not a file name", path != NULL ? path : "");
    }
    if (check_file_target(path, err, errlen) != 0 || odo_out_check_inputs(ins, path, err, errlen) != 0) {
        return -1;
    }
    (void)snprintf(o->path, sizeof o->path, "%s", path);
    parents_t *made = calloc(1, sizeof *made);
    if (made == NULL) {
        return odo_errf(err, errlen, "out of memory");
    }
    if (make_parents(dir, made, err, errlen) != 0) {
        parents_undo(made);
        free(made);
        return -1;
    }
    reg_node_t *reg = NULL;
    const int fd = open_temp(dir, base, o->tmp, &reg, err, errlen);
    if (fd < 0) {
        parents_undo(made);
        free(made);
        o->tmp[0] = '\0';
        return -1;
    }
    o->f = fdopen(fd, "w");
    if (o->f == NULL) {
        (void)close(fd);
        (void)unlink(o->tmp);
        reg_drop(reg);
        parents_undo(made);
        free(made);
        o->tmp[0] = '\0';
        return odo_errf(err, errlen, "%s: %s", path, strerror(errno));
    }
    o->reg = reg;
    o->parents = made;
    return 0;
}

void odo_out_file_abort(odo_out_file_t *o)
{
    if (o->f != NULL) {
        (void)fclose(o->f);
        o->f = NULL;
    }
    if (o->tmp[0] != '\0') {
        (void)unlink(o->tmp);
        o->tmp[0] = '\0';
    }
    reg_drop(o->reg);
    o->reg = NULL;
    parents_undo(o->parents);
    free(o->parents);
    o->parents = NULL;
}

int odo_out_file_commit(odo_out_file_t *o, char *err, size_t errlen)
{
    if (o->f == NULL) {
        odo_out_file_abort(o);
        return odo_errf(err, errlen, "%s: not open", o->path);
    }
    int bad = fflush(o->f) != 0 || ferror(o->f);
    int e = errno;
    if (!bad && fsync(fileno(o->f)) != 0) {
        bad = 1;
        e = errno;
    }
    if (fclose(o->f) != 0 && !bad) {
        bad = 1;
        e = errno;
    }
    o->f = NULL;
    if (bad) {
        (void)odo_errf(err, errlen, "cannot write %s: %s", o->path, strerror(e));
        odo_out_file_abort(o);
        return -1;
    }
    /* The target is checked again: a FIFO or link planted during the run is not replaced. */
    if (check_file_target(o->path, err, errlen) != 0) {
        odo_out_file_abort(o);
        return -1;
    }
    if (rename(o->tmp, o->path) != 0) {
        e = errno;
        (void)odo_errf(err, errlen, "cannot rename into %s: %s", o->path, strerror(e));
        odo_out_file_abort(o);
        return -1;
    }
    o->tmp[0] = '\0';
    reg_drop(o->reg);
    o->reg = NULL;
    char dir[PATH_MAX], base[PATH_MAX];
    if (split(o->path, dir, base) == 0) {
        fsync_dir(dir);
    }
    parents_keep(o->parents);
    free(o->parents);
    o->parents = NULL;
    return 0;
}

int odo_out_write(const char *path, const void *data, size_t len, const odo_out_inputs_t *ins, char *err, size_t errlen)
{
    odo_out_file_t o;
    if (odo_out_file_begin(&o, path, ins, err, errlen) != 0) {
        return -1;
    }
    if (len > 0U && fwrite(data, 1, len, o.f) != len) {
        const int e = errno;
        odo_out_file_abort(&o);
        return odo_errf(err, errlen, "cannot write %s: %s", path, strerror(e));
    }
    return odo_out_file_commit(&o, err, errlen);
}

/* ---------------------------------------------------------------------------------------------
 * Folders
 * ------------------------------------------------------------------------------------------- */

typedef enum { DIR_FRESH, DIR_UPDATE, DIR_FORCE } dir_mode_t;

typedef struct {
    reg_node_t *reg; /* the temp file or sub-folder */
    int is_dir;
    char name[];
} entry_t;

struct odo_out_dir {
    char path[PATH_MAX];
    char tmp[PATH_MAX];
    char tool[64];
    dir_mode_t mode;
    odo_out_inputs_t ins;
    reg_node_t *tmp_reg;
    parents_t made;
    entry_t **e; /* files and sub-folders written, in order */
    size_t n_e, cap_e;
    char **old; /* previous manifest's files (DIR_UPDATE) */
    size_t n_old;
};

/// A manifest name: relative, no "." / ".." / empty components, no control characters.
static int name_ok(const char *name)
{
    if (name == NULL || name[0] == '\0' || name[0] == '/' || strlen(name) >= 1024U) {
        return 0;
    }
    for (const char *c = name; *c != '\0'; ++c) {
        if ((unsigned char)*c < 0x20U || *c == 0x7F) {
            return 0;
        }
    }
    const char *s = name;
    for (;;) {
        const char *slash = strchr(s, '/');
        const size_t len = slash != NULL ? (size_t)(slash - s) : strlen(s);
        if (len == 0U || (len == 1U && s[0] == '.') || (len == 2U && s[0] == '.' && s[1] == '.')) {
            return 0;
        }
        if (slash == NULL) {
            return 1;
        }
        s = slash + 1;
    }
}

static void free_list(char **v, size_t n)
{
    for (size_t i = 0; i < n; ++i) {
        free(v[i]);
    }
    free(v);
}

/// Read dir's manifest. 1 if it is `tool`'s (names in *out), 0 if absent or foreign, -1 on I/O error.
static int read_manifest(const char *dir, const char *tool, char ***out, size_t *n_out, char *err, size_t errlen)
{
    char path[PATH_MAX];
    if (join(path, sizeof path, dir, ODO_OUT_MANIFEST) != 0) {
        return odo_errf(err, errlen, "%s: path too long", dir);
    }
    const int fd = open(path, O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0) {
        return (errno == ENOENT || errno == ELOOP) ? 0 : odo_errf(err, errlen, "%s: %s", path, strerror(errno));
    }
    FILE *f = fdopen(fd, "r");
    if (f == NULL) {
        (void)close(fd);
        return odo_errf(err, errlen, "%s: %s", path, strerror(errno));
    }
    char line[1100];
    char want[128];
    (void)snprintf(want, sizeof want, "tool %s\n", tool);
    int ours = fgets(line, sizeof line, f) != NULL && strcmp(line, ODO_OUT_MANIFEST_MAGIC "\n") == 0 &&
               fgets(line, sizeof line, f) != NULL && strcmp(line, want) == 0;
    char **v = NULL;
    size_t n = 0, cap = 0;
    while (ours && fgets(line, sizeof line, f) != NULL) {
        const size_t len = strlen(line);
        if (len == 0U || line[len - 1U] != '\n') {
            ours = 0; /* truncated or overlong: not a manifest we wrote */
            break;
        }
        line[len - 1U] = '\0';
        if (!name_ok(line) || strcmp(line, ODO_OUT_MANIFEST) == 0) {
            ours = 0;
            break;
        }
        if (n == cap) {
            cap = cap ? 2U * cap : 64U;
            char **nv = realloc(v, cap * sizeof *v);
            if (nv == NULL) {
                ours = 0;
                break;
            }
            v = nv;
        }
        v[n] = strdup(line);
        if (v[n] == NULL) {
            ours = 0;
            break;
        }
        n++;
    }
    (void)fclose(f);
    if (!ours) {
        free_list(v, n);
        return 0;
    }
    *out = v;
    *n_out = n;
    return 1;
}

/// 1 if path is an empty folder, 0 if it holds anything, -1 if it cannot be read.
static int dir_is_empty(const char *path)
{
    DIR *dd = opendir(path);
    if (dd == NULL) {
        return -1;
    }
    int empty = 1;
    for (struct dirent *e; (e = readdir(dd)) != NULL;) {
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0) {
            empty = 0;
            break;
        }
    }
    (void)closedir(dd);
    return empty;
}

void odo_out_dir_abort(odo_out_dir_t *d)
{
    if (d == NULL) {
        return;
    }
    /* Newest first: files before the sub-folders that hold them. */
    for (size_t i = d->n_e; i-- > 0U;) {
        entry_t *e = d->e[i];
        if (e->reg != NULL) {
            if (e->is_dir) {
                (void)rmdir(e->reg->path);
            } else {
                (void)unlink(e->reg->path);
            }
            reg_drop(e->reg);
        }
        free(e);
    }
    free(d->e);
    if (d->tmp_reg != NULL) {
        char m[PATH_MAX]; /* the manifest, if commit got that far */
        if (join(m, sizeof m, d->tmp, ODO_OUT_MANIFEST) == 0) {
            (void)unlink(m);
        }
        (void)rmdir(d->tmp);
        reg_drop(d->tmp_reg);
    }
    parents_undo(&d->made);
    free_list(d->old, d->n_old);
    free(d);
}

odo_out_dir_t *odo_out_dir_begin(const char *path, const char *tool, bool force, const odo_out_inputs_t *ins, char *err,
                                 size_t errlen)
{
    char dir[PATH_MAX], base[PATH_MAX];
    if (path == NULL || split(path, dir, base) != 0) {
        (void)odo_errf(err, errlen, "'%s' is not a folder name", path != NULL ? path : "");
        return NULL;
    }
    odo_out_dir_t *d = calloc(1, sizeof *d);
    if (d == NULL) {
        (void)odo_errf(err, errlen, "out of memory");
        return NULL;
    }
    (void)snprintf(d->path, sizeof d->path, "%s", path);
    (void)snprintf(d->tool, sizeof d->tool, "%s", tool);
    if (ins != NULL) {
        d->ins = *ins;
    }
    if (odo_out_check_inputs(ins, path, err, errlen) != 0) {
        odo_out_dir_abort(d);
        return NULL;
    }
    struct stat sb;
    if (lstat(path, &sb) == 0) {
        if (!S_ISDIR(sb.st_mode)) {
            (void)odo_errf(err, errlen, "%s is %s, not a folder; refusing to replace it", path, kind_of(sb.st_mode));
            odo_out_dir_abort(d);
            return NULL;
        }
        const int empty = dir_is_empty(path);
        if (empty < 0) {
            (void)odo_errf(err, errlen, "cannot read folder %s: %s", path, strerror(errno));
            odo_out_dir_abort(d);
            return NULL;
        }
        if (empty) {
            d->mode = DIR_FRESH;
        } else {
            const int m = read_manifest(path, tool, &d->old, &d->n_old, err, errlen);
            if (m < 0) {
                odo_out_dir_abort(d);
                return NULL;
            }
            if (m == 1) {
                d->mode = DIR_UPDATE;
            } else if (force) {
                d->mode = DIR_FORCE;
            } else {
                (void)odo_errf(err, errlen,
                               "%s is a non-empty folder %s did not write (no %s of its own in it); refusing to write "
                               "there (--force writes into it, replacing same-named files and removing nothing)",
                               path, tool, ODO_OUT_MANIFEST);
                odo_out_dir_abort(d);
                return NULL;
            }
        }
    } else if (errno != ENOENT && errno != ENOTDIR) {
        (void)odo_errf(err, errlen, "%s: %s", path, strerror(errno));
        odo_out_dir_abort(d);
        return NULL;
    } else {
        d->mode = DIR_FRESH;
    }
    if (make_parents(dir, &d->made, err, errlen) != 0) {
        odo_out_dir_abort(d);
        return NULL;
    }
    for (int attempt = 0;; ++attempt) {
        const int w = snprintf(d->tmp, sizeof d->tmp, "%s/.%s.tmp-%ld-%06lx", dir, base, (long)getpid(), next_suffix());
        if (w < 0 || (size_t)w >= sizeof d->tmp) {
            (void)odo_errf(err, errlen, "%s: path too long", path);
            odo_out_dir_abort(d);
            return NULL;
        }
        d->tmp_reg = reg_add(d->tmp, 1);
        if (d->tmp_reg == NULL) {
            (void)odo_errf(err, errlen, "out of memory");
            odo_out_dir_abort(d);
            return NULL;
        }
        if (mkdir(d->tmp, 0700) == 0) {
            break;
        }
        const int e = errno;
        reg_drop(d->tmp_reg);
        d->tmp_reg = NULL;
        if (e != EEXIST || attempt >= 100) {
            (void)odo_errf(err, errlen, "cannot create a temp folder beside %s: %s", path, strerror(e));
            odo_out_dir_abort(d);
            return NULL;
        }
    }
    return d;
}

const char *odo_out_dir_tmp(const odo_out_dir_t *d) { return d->tmp; }

static int has_entry(const odo_out_dir_t *d, const char *name)
{
    for (size_t i = 0; i < d->n_e; ++i) {
        if (strcmp(d->e[i]->name, name) == 0) {
            return 1;
        }
    }
    return 0;
}

static int add_entry(odo_out_dir_t *d, const char *name, int is_dir, reg_node_t *reg)
{
    if (d->n_e == d->cap_e) {
        const size_t cap = d->cap_e ? 2U * d->cap_e : 32U;
        entry_t **ne = realloc(d->e, cap * sizeof *ne);
        if (ne == NULL) {
            return -1;
        }
        d->e = ne;
        d->cap_e = cap;
    }
    const size_t len = strlen(name) + 1U;
    entry_t *e = malloc(sizeof *e + len);
    if (e == NULL) {
        return -1;
    }
    e->reg = reg;
    e->is_dir = is_dir;
    memcpy(e->name, name, len);
    d->e[d->n_e++] = e;
    return 0;
}

/// Sub-folders of name inside the temp folder, made and recorded.
static int make_subdirs(odo_out_dir_t *d, const char *name, char *err, size_t errlen)
{
    char rel[PATH_MAX];
    (void)snprintf(rel, sizeof rel, "%s", name);
    for (char *s = strchr(rel, '/'); s != NULL; s = strchr(s + 1, '/')) {
        *s = '\0';
        if (!has_entry(d, rel)) {
            char full[PATH_MAX];
            if (join(full, sizeof full, d->tmp, rel) != 0) {
                return odo_errf(err, errlen, "%s/%s: path too long", d->path, rel);
            }
            reg_node_t *r = reg_add(full, 1);
            if (r == NULL || mkdir(full, 0777) != 0) {
                const int e = errno;
                reg_drop(r);
                return odo_errf(err, errlen, "cannot create %s: %s", full, strerror(e));
            }
            if (add_entry(d, rel, 1, r) != 0) {
                (void)rmdir(full);
                reg_drop(r);
                return odo_errf(err, errlen, "out of memory");
            }
        }
        *s = '/';
    }
    return 0;
}

FILE *odo_out_dir_fopen(odo_out_dir_t *d, const char *name, char *err, size_t errlen)
{
    if (!name_ok(name) || strcmp(name, ODO_OUT_MANIFEST) == 0) {
        (void)odo_errf(err, errlen, "'%s' is not a file name an output folder may hold", name);
        return NULL;
    }
    if (has_entry(d, name)) {
        (void)odo_errf(err, errlen, "%s/%s written twice", d->path, name);
        return NULL;
    }
    if (make_subdirs(d, name, err, errlen) != 0) {
        return NULL;
    }
    char full[PATH_MAX];
    if (join(full, sizeof full, d->tmp, name) != 0) {
        (void)odo_errf(err, errlen, "%s/%s: path too long", d->path, name);
        return NULL;
    }
    reg_node_t *r = reg_add(full, 0);
    if (r == NULL) {
        (void)odo_errf(err, errlen, "out of memory");
        return NULL;
    }
    const int fd = open(full, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd < 0) {
        const int e = errno;
        reg_drop(r);
        (void)odo_errf(err, errlen, "cannot create %s: %s", full, strerror(e));
        return NULL;
    }
    FILE *f = fdopen(fd, "w");
    if (f == NULL || add_entry(d, name, 0, r) != 0) {
        const int e = errno;
        if (f != NULL) {
            (void)fclose(f);
        } else {
            (void)close(fd);
        }
        (void)unlink(full);
        reg_drop(r);
        (void)odo_errf(err, errlen, "cannot create %s: %s", full, strerror(e));
        return NULL;
    }
    return f;
}

int odo_out_dir_adopt(odo_out_dir_t *d, const char *name, char *err, size_t errlen)
{
    if (!name_ok(name) || strcmp(name, ODO_OUT_MANIFEST) == 0 || has_entry(d, name)) {
        return odo_errf(err, errlen, "'%s' cannot be adopted into %s", name, d->path);
    }
    char full[PATH_MAX];
    struct stat sb;
    if (join(full, sizeof full, d->tmp, name) != 0 || lstat(full, &sb) != 0 || !S_ISREG(sb.st_mode)) {
        return odo_errf(err, errlen, "%s is not a file the writer made", full);
    }
    reg_node_t *r = reg_add(full, 0);
    if (r == NULL || add_entry(d, name, 0, r) != 0) {
        reg_drop(r);
        return odo_errf(err, errlen, "out of memory");
    }
    return 0;
}

/// Write the manifest listing names (files only) to path via a temp file in the same folder.
static int write_manifest(const char *dir, const char *tool, char *const *names, size_t n, char *err, size_t errlen)
{
    char path[PATH_MAX];
    if (join(path, sizeof path, dir, ODO_OUT_MANIFEST) != 0) {
        return odo_errf(err, errlen, "%s: path too long", dir);
    }
    odo_out_file_t o;
    if (odo_out_file_begin(&o, path, NULL, err, errlen) != 0) {
        return -1;
    }
    fprintf(o.f, "%s\ntool %s\n", ODO_OUT_MANIFEST_MAGIC, tool);
    for (size_t i = 0; i < n; ++i) {
        fprintf(o.f, "%s\n", names[i]);
    }
    return odo_out_file_commit(&o, err, errlen);
}

static int in_list(char *const *v, size_t n, const char *s)
{
    for (size_t i = 0; i < n; ++i) {
        if (strcmp(v[i], s) == 0) {
            return 1;
        }
    }
    return 0;
}

static int fsync_path(const char *path)
{
    const int fd = open(path, O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0) {
        return -1;
    }
    const int rc = fsync(fd);
    return (close(fd) != 0 || rc != 0) ? -1 : 0;
}

int odo_out_dir_commit(odo_out_dir_t *d, char *err, size_t errlen)
{
    /* The files this run wrote, in order. */
    char **names = calloc(d->n_e + 1U, sizeof *names);
    size_t n = 0;
    if (names == NULL) {
        (void)odo_errf(err, errlen, "out of memory");
        odo_out_dir_abort(d);
        return -1;
    }
    for (size_t i = 0; i < d->n_e; ++i) {
        if (!d->e[i]->is_dir) {
            names[n++] = d->e[i]->name;
            if (fsync_path(d->e[i]->reg->path) != 0) {
                (void)odo_errf(err, errlen, "cannot write %s: %s", d->e[i]->reg->path, strerror(errno));
                free(names);
                odo_out_dir_abort(d);
                return -1;
            }
        }
    }
    const mode_t um = current_umask();
    int rc = 0;
    if (d->mode == DIR_FRESH) {
        if (write_manifest(d->tmp, d->tool, names, n, err, errlen) != 0 || chmod(d->tmp, 0777 & ~um) != 0) {
            rc = -1;
        } else {
            /* Checked again: something may have appeared at the target during the run. */
            struct stat sb;
            if (lstat(d->path, &sb) == 0 && (!S_ISDIR(sb.st_mode) || dir_is_empty(d->path) != 1)) {
                rc = odo_errf(err, errlen, "%s appeared during the run; not replacing it", d->path);
            } else if (rename(d->tmp, d->path) != 0) {
                rc = odo_errf(err, errlen, "cannot rename into %s: %s", d->path, strerror(errno));
            }
        }
        if (rc == 0) {
            /* Everything now lives under the target: nothing to clean up. */
            for (size_t i = 0; i < d->n_e; ++i) {
                reg_drop(d->e[i]->reg);
                d->e[i]->reg = NULL;
            }
            reg_drop(d->tmp_reg);
            d->tmp_reg = NULL;
            char parent[PATH_MAX], base[PATH_MAX];
            if (split(d->path, parent, base) == 0) {
                fsync_dir(parent);
            }
            parents_keep(&d->made);
        }
        free(names);
        if (rc != 0) {
            odo_out_dir_abort(d);
            return -1;
        }
        odo_out_dir_abort(d); /* frees what is left; the registry is empty */
        return 0;
    }

    /* Into an existing folder: check every destination before touching any. */
    for (size_t i = 0; i < d->n_e && rc == 0; ++i) {
        char dst[PATH_MAX];
        struct stat sb;
        if (join(dst, sizeof dst, d->path, d->e[i]->name) != 0) {
            rc = odo_errf(err, errlen, "%s/%s: path too long", d->path, d->e[i]->name);
        } else if (lstat(dst, &sb) == 0) {
            if (d->e[i]->is_dir ? !S_ISDIR(sb.st_mode) : !S_ISREG(sb.st_mode)) {
                rc = odo_errf(err, errlen, "%s is %s; refusing to replace it", dst, kind_of(sb.st_mode));
            } else if (!d->e[i]->is_dir) {
                rc = odo_out_check_inputs(&d->ins, dst, err, errlen);
            }
        }
    }
    /* The manifest first covers both runs, so a failure half-way leaves nothing unaccounted. */
    char **both = NULL;
    size_t n_both = 0;
    if (rc == 0) {
        both = calloc(n + d->n_old + 1U, sizeof *both);
        if (both == NULL) {
            rc = odo_errf(err, errlen, "out of memory");
        } else {
            for (size_t i = 0; i < n; ++i) {
                both[n_both++] = names[i];
            }
            for (size_t i = 0; i < d->n_old; ++i) {
                if (!in_list(names, n, d->old[i])) {
                    both[n_both++] = d->old[i];
                }
            }
            rc = write_manifest(d->path, d->tool, both, n_both, err, errlen);
        }
    }
    for (size_t i = 0; i < d->n_e && rc == 0; ++i) {
        entry_t *e = d->e[i];
        char dst[PATH_MAX];
        (void)join(dst, sizeof dst, d->path, e->name);
        if (e->is_dir) {
            struct stat sb;
            if (lstat(dst, &sb) != 0 && mkdir(dst, 0777) != 0) {
                rc = odo_errf(err, errlen, "cannot create folder %s: %s", dst, strerror(errno));
            }
        } else if (rename(e->reg->path, dst) != 0) {
            rc = odo_errf(err, errlen, "cannot rename into %s: %s", dst, strerror(errno));
        } else {
            reg_drop(e->reg);
            e->reg = NULL;
        }
    }
    if (rc == 0 && d->mode == DIR_UPDATE) {
        /* Files of the previous run that this one no longer writes: ours, so removed. */
        for (size_t i = 0; i < d->n_old; ++i) {
            if (in_list(names, n, d->old[i])) {
                continue;
            }
            char dst[PATH_MAX];
            struct stat sb;
            if (join(dst, sizeof dst, d->path, d->old[i]) == 0 && lstat(dst, &sb) == 0 && S_ISREG(sb.st_mode) &&
                odo_out_check_inputs(&d->ins, dst, NULL, 0) == 0) {
                (void)unlink(dst);
            }
        }
    }
    if (rc == 0) {
        rc = write_manifest(d->path, d->tool, names, n, err, errlen);
    }
    if (rc == 0) {
        fsync_dir(d->path);
        parents_keep(&d->made);
    }
    free(both);
    free(names);
    odo_out_dir_abort(d); /* removes the (now empty) temp folder */
    return rc;
}
