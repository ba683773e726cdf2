/// odo_out: the one output rule of every host tool that writes files (issue 16 item 2).
///
/// Scope: host C only (POSIX.1-2008). Used by host_sim and tools; uses nothing of theirs.
/// The Python twin is tools/python/odo_tools/outpath.py; both read and write the same manifest
/// (ODO_OUT_MANIFEST, format below), tested against each other.
///
/// The rule:
///  - Missing parent folders are created (0777 & ~umask) and removed again if the run fails.
///  - A file output is written into a fresh temp beside the target, opened with
///    O_CREAT|O_EXCL|O_NOFOLLOW (mode 0666 & ~umask), fsync'd and renamed into place. The target,
///    if it exists, must be a regular file: a folder, symlink, FIFO, device or socket is refused
///    with an error naming it. A symlink planted at a temp name is never followed (O_EXCL).
///  - A folder output is built in a fresh temp folder beside the target. If the target does not
///    exist or is empty, the temp folder is renamed into place. If it holds a manifest written by
///    the same tool, exactly the files of that manifest may be replaced or removed; everything else
///    stays. A non-empty folder without such a manifest is refused unless `force`, and with force the
///    tool's files replace same-named files and nothing else is removed.
///  - An output that is also an input (same device and inode as an input file or folder, or inside
///    an input folder) is refused before anything is written.
///  - Temps (and parents created for them) are removed on every error path, at exit, on
///    SIGINT/SIGTERM/SIGHUP/SIGABRT (when the signal had its default action) and after a
///    sanitizer report (__sanitizer_set_death_callback); a failed run leaves the target as it was.
///
/// Manifest (ODO_OUT_MANIFEST in the output folder, text, LF line ends):
///   line 1 "odo-out-manifest 1", line 2 "tool NAME", then one relative path per line (no "..",
///   no leading "/", no empty component). A manifest naming anything else is ignored as foreign.
///
/// Errors: every function that can fail returns 0 on success and -1 on failure with a one-line,
/// NUL-terminated message naming the path in err (never longer than errlen - 1). Not thread-safe;
/// the signal cleanup is async-signal-safe.
#ifndef ODO_OUT_H
#define ODO_OUT_H

#include <limits.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <sys/types.h>

#ifdef __cplusplus
extern "C" {
#endif

#define ODO_OUT_MANIFEST       ".odo-manifest"
#define ODO_OUT_MANIFEST_MAGIC "odo-out-manifest 1"

/// The identities (device, inode) of a tool's inputs, taken before any output is opened.
typedef struct {
    size_t n;
    struct {
        dev_t dev;
        ino_t ino;
        bool is_dir;
        char path[PATH_MAX];
    } in[32];
} odo_out_inputs_t;

/// Empty set.
void odo_out_inputs_init(odo_out_inputs_t *ins);

/// Add an input (file or folder; NULL and paths that do not exist are skipped: the tool reports
/// those when it reads them). Returns -1 only when more than 32 inputs are added.
int odo_out_inputs_add(odo_out_inputs_t *ins, const char *path, char *err, size_t errlen);

/// 0 if writing `path` cannot touch an input: `path` is not an input (same device and inode) and
/// no existing ancestor of it is an input folder. -1 with a message naming both otherwise.
int odo_out_check_inputs(const odo_out_inputs_t *ins, const char *path, char *err, size_t errlen);

/// One file being written. `f` is the stream to write to (fully buffered).
typedef struct {
    FILE *f;
    char path[PATH_MAX]; /* target */
    char tmp[PATH_MAX];  /* temp beside it; "" once committed or aborted */
    void *reg;           /* cleanup registration */
    void *parents;       /* parent folders this file created */
} odo_out_file_t;

/// Check the target (regular file or absent, not an input; ins may be NULL), create missing
/// parents and open a fresh temp beside it. On failure nothing is left behind.
int odo_out_file_begin(odo_out_file_t *o, const char *path, const odo_out_inputs_t *ins, char *err, size_t errlen);

/// Flush, fsync, close and rename into place (the target is checked again just before). On failure
/// the temp is removed and the target is as it was.
int odo_out_file_commit(odo_out_file_t *o, char *err, size_t errlen);

/// Close and remove the temp (and the parents begin created). Safe to call twice or after commit.
void odo_out_file_abort(odo_out_file_t *o);

/// begin + write len bytes + commit.
int odo_out_write(const char *path, const void *data, size_t len, const odo_out_inputs_t *ins, char *err,
                  size_t errlen);

/// One output folder being built.
typedef struct odo_out_dir odo_out_dir_t;

/// Check the target folder (absent, empty, holding `tool`'s manifest, or any folder with force;
/// not an input nor inside one; not a symlink or a non-folder), create missing parents and a fresh
/// temp folder beside it. Returns NULL with err set on failure (nothing left behind).
odo_out_dir_t *odo_out_dir_begin(const char *path, const char *tool, bool force, const odo_out_inputs_t *ins, char *err,
                                 size_t errlen);

/// Open `name` (relative, may contain subfolders) for writing inside the temp folder. The caller
/// writes and fclose()s it (checking the result) before odo_out_dir_commit. NULL with err set on a
/// bad name, a name opened twice, or an I/O error.
FILE *odo_out_dir_fopen(odo_out_dir_t *d, const char *name, char *err, size_t errlen);

/// The temp folder's path (to pass to writers that take a folder; register what they write with
/// odo_out_dir_adopt).
const char *odo_out_dir_tmp(const odo_out_dir_t *d);

/// Record a file that another writer created at odo_out_dir_tmp(d)/name.
int odo_out_dir_adopt(odo_out_dir_t *d, const char *name, char *err, size_t errlen);

/// fsync every file, write the manifest and put the files into place as the rule above says; then
/// free d. On failure the temp is removed, d is freed and the target holds what it held before
/// (or, for a failure between two renames into an existing folder, a manifest that covers both
/// runs' files, so the next run cleans up).
int odo_out_dir_commit(odo_out_dir_t *d, char *err, size_t errlen);

/// Remove the temp folder and what is in it, remove parents begin created, free d. NULL is fine.
void odo_out_dir_abort(odo_out_dir_t *d);

/// Tests only: temp names end in -PID-%06lx of seed, seed + 1, ... (0: back to unpredictable), so a
/// test can plant a link where the next temp will go and see it is not followed.
void odo_out_test_temp_names(unsigned long seed);

/// Remove every temp this process still has (async-signal-safe; also run at exit and on signals).
void odo_out_cleanup_now(void);

#ifdef __cplusplus
}
#endif
#endif /* ODO_OUT_H */
