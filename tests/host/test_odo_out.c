/// The output rule (issue 16 item 2, hostlib/odo_out.h): every rule has a test here, each in a
/// fresh temp folder of its own. Special files are a FIFO or a symlink the test makes itself,
/// never a real /dev node (as root a wrong rename would replace it).
#include "check_support.h"
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "odo_out.h"

static char g_root[PATH_MAX / 2];

static const char *at(const char *rel)
{
    static char buf[4][PATH_MAX];
    static int k = 0;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/%s", g_root, rel);
    return buf[k];
}

static void put(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    fputs(text, f);
    ck_assert_int_eq(fclose(f), 0);
}

/// The file's text ("<missing>" if it cannot be read), in a static buffer.
static const char *get(const char *path)
{
    static char buf[4096];
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        return "<missing>";
    }
    const size_t n = fread(buf, 1, sizeof buf - 1, f);
    buf[n] = '\0';
    fclose(f);
    return buf;
}

/// Number of entries in a folder, and how many of them look like our temps (".*.tmp-").
static int count(const char *dir, int *temps)
{
    DIR *d = opendir(dir);
    ck_assert_ptr_nonnull(d);
    int n = 0;
    if (temps != NULL) {
        *temps = 0;
    }
    for (struct dirent *e; (e = readdir(d)) != NULL;) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) {
            continue;
        }
        n++;
        if (temps != NULL && strstr(e->d_name, ".tmp-") != NULL) {
            (*temps)++;
        }
    }
    closedir(d);
    return n;
}

/// In a forked child: the default actions back (Check's runner has its own SIGINT/SIGTERM handler,
/// which a tool would keep), so odo_out installs its cleanup as it would in a CLI.
static void child_default_signals(void)
{
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    signal(SIGHUP, SIG_DFL);
}

static void rm_rf(const char *path)
{
    char cmd[PATH_MAX + 32];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", path);
    ck_assert_int_eq(system(cmd), 0);
}

static void setup(void)
{
    snprintf(g_root, sizeof g_root, "%s/odo_out_XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    ck_assert_ptr_nonnull(mkdtemp(g_root));
}

static void teardown(void)
{
    odo_out_test_temp_names(0);
    rm_rf(g_root);
}

static int write_dir(const char *path, const char *tool, bool force, const odo_out_inputs_t *ins,
                     const char *const *names, size_t n, const char *text, char *err)
{
    odo_out_dir_t *d = odo_out_dir_begin(path, tool, force, ins, err, 512);
    if (d == NULL) {
        return -1;
    }
    for (size_t i = 0; i < n; ++i) {
        FILE *f = odo_out_dir_fopen(d, names[i], err, 512);
        ck_assert_msg(f != NULL, "%s", err);
        fputs(text, f);
        ck_assert_int_eq(fclose(f), 0);
    }
    return odo_out_dir_commit(d, err, 512);
}

/* ---- files ---------------------------------------------------------------------------------- */

START_TEST(file_missing_parents_are_created_and_nothing_else_is_left)
{
    char err[512];
    ck_assert_int_eq(odo_out_write(at("a/b/c.txt"), "hello\n", 6, NULL, err, sizeof err), 0);
    ck_assert_str_eq(get(at("a/b/c.txt")), "hello\n");
    int temps;
    ck_assert_int_eq(count(at("a/b"), &temps), 1);
    ck_assert_int_eq(temps, 0);
    struct stat sb;
    ck_assert_int_eq(stat(at("a/b/c.txt"), &sb), 0);
    const mode_t um = umask(022);
    umask(um);
    ck_assert_uint_eq(sb.st_mode & 0777U, 0666U & ~um); /* 0666 & ~umask, like any new file */
}
END_TEST

START_TEST(file_replaces_a_regular_file_whole)
{
    char err[512];
    put(at("p.json"), "old content that is longer\n");
    ck_assert_int_eq(odo_out_write(at("p.json"), "new\n", 4, NULL, err, sizeof err), 0);
    ck_assert_str_eq(get(at("p.json")), "new\n");
}
END_TEST

START_TEST(file_refuses_fifo_symlink_and_folder_targets)
{
    char err[512];
    ck_assert_int_eq(mkfifo(at("fifo"), 0600), 0);
    ck_assert_int_eq(odo_out_write(at("fifo"), "x", 1, NULL, err, sizeof err), -1);
    ck_assert_ptr_nonnull(strstr(err, "a FIFO"));
    ck_assert_ptr_nonnull(strstr(err, "fifo"));
    struct stat sb;
    ck_assert_int_eq(lstat(at("fifo"), &sb), 0);
    ck_assert(S_ISFIFO(sb.st_mode));

    put(at("victim"), "keep\n");
    ck_assert_int_eq(symlink(at("victim"), at("link")), 0);
    ck_assert_int_eq(odo_out_write(at("link"), "x", 1, NULL, err, sizeof err), -1);
    ck_assert_ptr_nonnull(strstr(err, "symbolic link"));
    ck_assert_int_eq(lstat(at("link"), &sb), 0);
    ck_assert(S_ISLNK(sb.st_mode));
    ck_assert_str_eq(get(at("victim")), "keep\n");

    ck_assert_int_eq(mkdir(at("dir"), 0700), 0);
    ck_assert_int_eq(odo_out_write(at("dir"), "x", 1, NULL, err, sizeof err), -1);
    ck_assert_ptr_nonnull(strstr(err, "a folder"));
    int temps;
    ck_assert_int_eq(count(g_root, &temps), 4); /* fifo, victim, link, dir: nothing added */
    ck_assert_int_eq(temps, 0);
}
END_TEST

START_TEST(file_never_follows_a_symlink_planted_at_the_temp_name)
{
    char err[512];
    put(at("victim"), "keep\n");
    /* The next temp name for out.json, predicted from the test seed. */
    odo_out_test_temp_names(0x100);
    char planted[PATH_MAX];
    snprintf(planted, sizeof planted, "%s/.out.json.tmp-%ld-%06lx", g_root, (long)getpid(), 0x100UL);
    ck_assert_int_eq(symlink(at("victim"), planted), 0);
    ck_assert_int_eq(odo_out_write(at("out.json"), "new\n", 4, NULL, err, sizeof err), 0);
    ck_assert_str_eq(get(at("out.json")), "new\n");
    ck_assert_str_eq(get(at("victim")), "keep\n");
    struct stat sb;
    ck_assert_int_eq(lstat(planted, &sb), 0); /* not ours: left alone */
    ck_assert(S_ISLNK(sb.st_mode));
}
END_TEST

START_TEST(file_that_is_an_input_is_refused_before_anything_is_written)
{
    char err[512];
    put(at("returns.csv"), "run,direction\n");
    odo_out_inputs_t ins;
    odo_out_inputs_init(&ins);
    ck_assert_int_eq(odo_out_inputs_add(&ins, at("returns.csv"), err, sizeof err), 0);
    ck_assert_int_eq(odo_out_write(at("returns.csv"), "x", 1, &ins, err, sizeof err), -1);
    ck_assert_ptr_nonnull(strstr(err, "also an input"));
    ck_assert_str_eq(get(at("returns.csv")), "run,direction\n");
    /* The same file by another name (a hard link, "./x/../") is the same input. */
    ck_assert_int_eq(link(at("returns.csv"), at("alias.csv")), 0);
    ck_assert_int_eq(odo_out_write(at("alias.csv"), "x", 1, &ins, err, sizeof err), -1);
    ck_assert_int_eq(mkdir(at("x"), 0700), 0);
    ck_assert_int_eq(odo_out_write(at("x/../returns.csv"), "x", 1, &ins, err, sizeof err), -1);
    ck_assert_str_eq(get(at("returns.csv")), "run,direction\n");
    int temps;
    ck_assert_int_eq(count(g_root, &temps), 3);
    ck_assert_int_eq(temps, 0);
}
END_TEST

START_TEST(file_inside_an_input_folder_is_refused)
{
    char err[512];
    ck_assert_int_eq(mkdir(at("runs"), 0700), 0);
    ck_assert_int_eq(mkdir(at("runs/a"), 0700), 0);
    odo_out_inputs_t ins;
    odo_out_inputs_init(&ins);
    ck_assert_int_eq(odo_out_inputs_add(&ins, at("runs"), err, sizeof err), 0);
    ck_assert_int_eq(odo_out_write(at("runs/a/new/p.json"), "x", 1, &ins, err, sizeof err), -1);
    ck_assert_ptr_nonnull(strstr(err, "inside the input folder"));
    ck_assert_int_eq(count(at("runs/a"), NULL), 0); /* not even the parent "new" */
    ck_assert_int_eq(odo_out_write(at("elsewhere.json"), "x", 1, &ins, err, sizeof err), 0);
}
END_TEST

START_TEST(file_abort_leaves_the_target_and_folders_as_they_were)
{
    char err[512];
    put(at("keep.json"), "old\n");
    odo_out_file_t o;
    ck_assert_int_eq(odo_out_file_begin(&o, at("keep.json"), NULL, err, sizeof err), 0);
    fputs("half", o.f);
    odo_out_file_abort(&o);
    ck_assert_str_eq(get(at("keep.json")), "old\n");
    ck_assert_int_eq(odo_out_file_begin(&o, at("n1/n2/f.json"), NULL, err, sizeof err), 0);
    odo_out_file_abort(&o);
    odo_out_file_abort(&o);                   /* twice is fine */
    ck_assert_int_eq(count(g_root, NULL), 1); /* the parents made for it are gone too */
}
END_TEST

START_TEST(file_temp_is_removed_when_a_signal_ends_the_run)
{
    static const int sigs[] = {SIGINT, SIGTERM, SIGHUP};
    for (size_t k = 0; k < sizeof sigs / sizeof sigs[0]; ++k) {
        const pid_t pid = fork();
        ck_assert_int_ge(pid, 0);
        if (pid == 0) {
            child_default_signals();
            char err[512];
            odo_out_file_t o;
            if (odo_out_file_begin(&o, at("deep/sig.json"), NULL, err, sizeof err) != 0) {
                _exit(3);
            }
            fputs("partial", o.f);
            fflush(o.f);
            raise(sigs[k]);
            _exit(4); /* not reached: the handler re-raises with the default action */
        }
        int status = 0;
        ck_assert_int_eq(waitpid(pid, &status, 0), pid);
        ck_assert(WIFSIGNALED(status));
        ck_assert_int_eq(WTERMSIG(status), sigs[k]);
        ck_assert_int_eq(count(g_root, NULL), 0); /* no temp, no "deep" */
    }
}
END_TEST

START_TEST(file_temp_is_removed_when_the_tool_exits_without_committing)
{
    const pid_t pid = fork();
    ck_assert_int_ge(pid, 0);
    if (pid == 0) {
        child_default_signals();
        char err[512];
        odo_out_file_t o;
        if (odo_out_file_begin(&o, at("x.json"), NULL, err, sizeof err) != 0) {
            _exit(3);
        }
        fputs("partial", o.f);
        exit(1); /* an error path that forgot to abort */
    }
    int status = 0;
    ck_assert_int_eq(waitpid(pid, &status, 0), pid);
    ck_assert(WIFEXITED(status));
    ck_assert_int_eq(WEXITSTATUS(status), 1);
    ck_assert_int_eq(count(g_root, NULL), 0);
}
END_TEST

/* ---- folders -------------------------------------------------------------------------------- */

static const char *const k_two[] = {"a.log", "summary.json"};

START_TEST(dir_fresh_is_built_beside_and_renamed_into_place_with_its_manifest)
{
    char err[512];
    ck_assert_int_eq(write_dir(at("out/run"), "odo-test", false, NULL, k_two, 2, "1\n", err), 0);
    ck_assert_str_eq(get(at("out/run/a.log")), "1\n");
    ck_assert_str_eq(get(at("out/run/" ODO_OUT_MANIFEST)),
                     ODO_OUT_MANIFEST_MAGIC "\ntool odo-test\na.log\nsummary.json\n");
    int temps;
    ck_assert_int_eq(count(at("out"), &temps), 1);
    ck_assert_int_eq(temps, 0);
    /* An existing empty folder is taken as fresh. */
    ck_assert_int_eq(mkdir(at("empty"), 0700), 0);
    ck_assert_int_eq(write_dir(at("empty"), "odo-test", false, NULL, k_two, 2, "2\n", err), 0);
    ck_assert_str_eq(get(at("empty/summary.json")), "2\n");
}
END_TEST

START_TEST(dir_foreign_non_empty_folder_is_refused_and_untouched)
{
    char err[512];
    ck_assert_int_eq(mkdir(at("mine"), 0700), 0);
    put(at("mine/summary.json"), "user's\n"); /* the old odo-sim marker no longer counts */
    put(at("mine/notes.txt"), "user's\n");
    ck_assert_int_eq(write_dir(at("mine"), "odo-sim", false, NULL, k_two, 2, "x\n", err), -1);
    ck_assert_ptr_nonnull(strstr(err, "--force"));
    ck_assert_ptr_nonnull(strstr(err, at("mine")));
    ck_assert_str_eq(get(at("mine/summary.json")), "user's\n");
    ck_assert_int_eq(count(at("mine"), NULL), 2);
    int temps;
    ck_assert_int_eq(count(g_root, &temps), 1);
    ck_assert_int_eq(temps, 0);
}
END_TEST

START_TEST(dir_force_writes_its_files_and_removes_nothing_else)
{
    char err[512];
    ck_assert_int_eq(mkdir(at("mine"), 0700), 0);
    put(at("mine/summary.json"), "user's\n");
    put(at("mine/notes.txt"), "user's\n");
    ck_assert_int_eq(write_dir(at("mine"), "odo-sim", true, NULL, k_two, 2, "x\n", err), 0);
    ck_assert_str_eq(get(at("mine/summary.json")), "x\n");
    ck_assert_str_eq(get(at("mine/a.log")), "x\n");
    ck_assert_str_eq(get(at("mine/notes.txt")), "user's\n");
    ck_assert_int_eq(count(at("mine"), NULL), 4); /* + the manifest */
}
END_TEST

START_TEST(dir_rerun_replaces_exactly_its_previous_files)
{
    char err[512];
    static const char *const first[] = {"run-cw-01.log", "run-cw-02.log", "sub/r.csv", "summary.json"};
    static const char *const second[] = {"run-cw-01.log", "summary.json"};
    ck_assert_int_eq(write_dir(at("o"), "odo-sim", false, NULL, first, 4, "1\n", err), 0);
    put(at("o/notes.txt"), "user's\n"); /* the user adds a file between runs */
    ck_assert_int_eq(write_dir(at("o"), "odo-sim", false, NULL, second, 2, "2\n", err), 0);
    ck_assert_str_eq(get(at("o/run-cw-01.log")), "2\n");
    ck_assert_str_eq(get(at("o/run-cw-02.log")), "<missing>"); /* ours, no longer written */
    ck_assert_str_eq(get(at("o/sub/r.csv")), "<missing>");
    ck_assert_str_eq(get(at("o/notes.txt")), "user's\n");
    ck_assert_str_eq(get(at("o/" ODO_OUT_MANIFEST)),
                     ODO_OUT_MANIFEST_MAGIC "\ntool odo-sim\nrun-cw-01.log\nsummary.json\n");
    /* Another tool's manifest is foreign. */
    ck_assert_int_eq(write_dir(at("o"), "odo-replay", false, NULL, second, 2, "3\n", err), -1);
    ck_assert_str_eq(get(at("o/summary.json")), "2\n");
}
END_TEST

START_TEST(dir_manifest_naming_paths_outside_is_foreign)
{
    char err[512];
    put(at("precious"), "keep\n");
    ck_assert_int_eq(mkdir(at("o"), 0700), 0);
    put(at("o/" ODO_OUT_MANIFEST), ODO_OUT_MANIFEST_MAGIC "\ntool odo-sim\n../precious\n");
    ck_assert_int_eq(write_dir(at("o"), "odo-sim", false, NULL, k_two, 2, "x\n", err), -1);
    put(at("o/" ODO_OUT_MANIFEST), ODO_OUT_MANIFEST_MAGIC "\ntool odo-sim\n/etc/hostname\n");
    ck_assert_int_eq(write_dir(at("o"), "odo-sim", false, NULL, k_two, 2, "x\n", err), -1);
    put(at("o/" ODO_OUT_MANIFEST), ODO_OUT_MANIFEST_MAGIC "\ntool odo-sim\ntruncated"); /* no newline */
    ck_assert_int_eq(write_dir(at("o"), "odo-sim", false, NULL, k_two, 2, "x\n", err), -1);
    ck_assert_str_eq(get(at("precious")), "keep\n");
}
END_TEST

START_TEST(dir_refuses_file_symlink_and_input_targets)
{
    char err[512];
    put(at("file"), "keep\n");
    ck_assert_int_eq(write_dir(at("file"), "odo-sim", true, NULL, k_two, 2, "x\n", err), -1);
    ck_assert_ptr_nonnull(strstr(err, "not a folder"));
    ck_assert_int_eq(mkdir(at("real"), 0700), 0);
    ck_assert_int_eq(symlink(at("real"), at("link")), 0);
    ck_assert_int_eq(write_dir(at("link"), "odo-sim", true, NULL, k_two, 2, "x\n", err), -1);
    ck_assert_ptr_nonnull(strstr(err, "symbolic link"));

    /* odo-import/odo-gap with --out equal to the input folder: the recorded runs stay. */
    ck_assert_int_eq(mkdir(at("runs"), 0700), 0);
    put(at("runs/run-01.csv"), "t,l,r\n");
    odo_out_inputs_t ins;
    odo_out_inputs_init(&ins);
    ck_assert_int_eq(odo_out_inputs_add(&ins, at("runs"), err, sizeof err), 0);
    ck_assert_int_eq(write_dir(at("runs"), "odo-import", true, &ins, k_two, 2, "x\n", err), -1);
    ck_assert_ptr_nonnull(strstr(err, "also an input"));
    ck_assert_int_eq(write_dir(at("runs/out"), "odo-import", true, &ins, k_two, 2, "x\n", err), -1);
    ck_assert_ptr_nonnull(strstr(err, "inside the input folder"));
    ck_assert_int_eq(count(at("runs"), NULL), 1);
    ck_assert_str_eq(get(at("runs/run-01.csv")), "t,l,r\n");

    /* --force into a folder holding an input file of the same name as an output. */
    ck_assert_int_eq(mkdir(at("f"), 0700), 0);
    put(at("f/summary.json"), "input\n");
    odo_out_inputs_init(&ins);
    ck_assert_int_eq(odo_out_inputs_add(&ins, at("f/summary.json"), err, sizeof err), 0);
    ck_assert_int_eq(write_dir(at("f"), "odo-sim", true, &ins, k_two, 2, "x\n", err), -1);
    ck_assert_str_eq(get(at("f/summary.json")), "input\n");
    ck_assert_int_eq(count(at("f"), NULL), 1); /* a.log was not moved in either */
}
END_TEST

START_TEST(dir_abort_and_signals_leave_nothing)
{
    char err[512];
    odo_out_dir_t *d = odo_out_dir_begin(at("p/q/out"), "odo-sim", false, NULL, err, sizeof err);
    ck_assert_ptr_nonnull(d);
    FILE *f = odo_out_dir_fopen(d, "x/y.log", err, sizeof err);
    ck_assert_ptr_nonnull(f);
    fclose(f);
    ck_assert_ptr_null(odo_out_dir_fopen(d, "x/y.log", err, sizeof err)); /* twice */
    ck_assert_ptr_null(odo_out_dir_fopen(d, "../escape", err, sizeof err));
    ck_assert_ptr_null(odo_out_dir_fopen(d, ODO_OUT_MANIFEST, err, sizeof err));
    odo_out_dir_abort(d);
    ck_assert_int_eq(count(g_root, NULL), 0);

    const pid_t pid = fork();
    ck_assert_int_ge(pid, 0);
    if (pid == 0) {
        child_default_signals();
        odo_out_dir_t *c = odo_out_dir_begin(at("p/out"), "odo-sim", false, NULL, err, sizeof err);
        if (c == NULL) {
            _exit(3);
        }
        FILE *g = odo_out_dir_fopen(c, "s/a.log", err, sizeof err);
        if (g == NULL) {
            _exit(3);
        }
        fputs("x", g);
        fclose(g);
        raise(SIGTERM);
        _exit(4);
    }
    int status = 0;
    ck_assert_int_eq(waitpid(pid, &status, 0), pid);
    ck_assert(WIFSIGNALED(status));
    ck_assert_int_eq(count(g_root, NULL), 0);
}
END_TEST

static Suite *suite(void)
{
    Suite *s = suite_create("odo_out");
    TCase *tf = tcase_create("file");
    tcase_add_checked_fixture(tf, setup, teardown);
    tcase_add_test(tf, file_missing_parents_are_created_and_nothing_else_is_left);
    tcase_add_test(tf, file_replaces_a_regular_file_whole);
    tcase_add_test(tf, file_refuses_fifo_symlink_and_folder_targets);
    tcase_add_test(tf, file_never_follows_a_symlink_planted_at_the_temp_name);
    tcase_add_test(tf, file_that_is_an_input_is_refused_before_anything_is_written);
    tcase_add_test(tf, file_inside_an_input_folder_is_refused);
    tcase_add_test(tf, file_abort_leaves_the_target_and_folders_as_they_were);
    tcase_add_test(tf, file_temp_is_removed_when_a_signal_ends_the_run);
    tcase_add_test(tf, file_temp_is_removed_when_the_tool_exits_without_committing);
    suite_add_tcase(s, tf);
    TCase *td = tcase_create("folder");
    tcase_add_checked_fixture(td, setup, teardown);
    tcase_add_test(td, dir_fresh_is_built_beside_and_renamed_into_place_with_its_manifest);
    tcase_add_test(td, dir_foreign_non_empty_folder_is_refused_and_untouched);
    tcase_add_test(td, dir_force_writes_its_files_and_removes_nothing_else);
    tcase_add_test(td, dir_rerun_replaces_exactly_its_previous_files);
    tcase_add_test(td, dir_manifest_naming_paths_outside_is_foreign);
    tcase_add_test(td, dir_refuses_file_symlink_and_input_targets);
    tcase_add_test(td, dir_abort_and_signals_leave_nothing);
    suite_add_tcase(s, td);
    return s;
}

int main(void) { return ts_run_suite(suite()); }
