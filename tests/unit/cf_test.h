/* SPDX-License-Identifier: MIT */
/* cf_test.h: cmocka includes and the numeric assertions the tests share. */
#ifndef CF_TEST_H
#define CF_TEST_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

/* |a - b| <= tol, reporting both values (cmocka 1.1 lacks a double form). */
#define assert_near(a, b, tol)                                                                     \
    do {                                                                                           \
        double a_ = (a), b_ = (b), t_ = (tol);                                                     \
        if (!(fabs(a_ - b_) <= t_))                                                                \
            fail_msg("%s = %.17g, %s = %.17g, |diff| %.3g > %.3g", #a, a_, #b, b_, fabs(a_ - b_),  \
                     t_);                                                                          \
    } while (0)

#endif
