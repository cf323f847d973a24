/*
 * The C test programs' checks: each counts a pass or prints what failed, and the program ends
 * with the line "N passed, M failed" that capi/tests/c_programs.rs reads.
 */
#ifndef VKL_TEST_EXPECT_H
#define VKL_TEST_EXPECT_H

#include <stdio.h>
#include <string.h>

#include <vklens.h>

static int passed, failed;

static inline void expect(const char *what, int ok) {
    if (ok) {
        passed++;
    } else {
        failed++;
        fprintf(stderr, "FAIL %s\n", what);
    }
}

/* Expects success; frees an error. Returns whether it succeeded. */
static inline int expect_ok(const char *what, vkl_error e) {
    if (e == NULL) {
        passed++;
        return 1;
    }
    failed++;
    fprintf(stderr, "FAIL %s: %s\n", what, vkl_error_message(e));
    vkl_error_free(&e);
    return 0;
}

/* Expects `e` to be an error of `kind` whose message contains `name` (and `also`, when not
 * NULL); frees it, and checks that freeing nulled the handle. */
static inline void expect_error2(const char *what, vkl_error e, vkl_error_kind kind, const char *name,
                                 const char *also) {
    const char *msg = vkl_error_message(e);
    if (e && vkl_error_kind_of(e) == kind && strstr(msg, name) && (!also || strstr(msg, also))) {
        passed++;
    } else {
        failed++;
        fprintf(stderr, "FAIL %s: kind %d (want %d), message \"%s\" (want it to name \"%s\"%s%s)\n", what,
                (int)vkl_error_kind_of(e), (int)kind, msg, name, also ? " and " : "", also ? also : "");
    }
    vkl_error_free(&e);
    if (e != NULL) {
        failed++;
        fprintf(stderr, "FAIL %s: vkl_error_free did not null the handle\n", what);
    }
}

/* Expects `e` to be an error of `kind` whose message contains `name`; frees it. */
static inline void expect_error(const char *what, vkl_error e, vkl_error_kind kind, const char *name) {
    expect_error2(what, e, kind, name, NULL);
}

#endif
