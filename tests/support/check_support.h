/// Shared tail of every Check test program (tests/host, host_sim/tests).
#ifndef CHECK_SUPPORT_H
#define CHECK_SUPPORT_H

#include <check.h>

/// Run every test of a suite with normal output; the process exit code: 0 iff all passed.
static inline int ts_run_suite(Suite *s)
{
    SRunner *sr = srunner_create(s);
    srunner_run_all(sr, CK_NORMAL);
    const int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed == 0 ? 0 : 1;
}

#endif
