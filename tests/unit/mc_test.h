/* Shared by the cmocka unit tests: the includes cmocka needs, and assert_near. */
#ifndef MC_TEST_H
#define MC_TEST_H
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>

#define PI_D 3.14159265358979323846

/* assert |a - b| <= tol with the values in the failure message */
#define assert_near(a, b, tol)                                                               \
    do {                                                                                     \
        double a_ = (double)(a), b_ = (double)(b), t_ = (double)(tol);                       \
        if (!(fabs(a_ - b_) <= t_)) {                                                        \
            fail_msg("%s = %.9g, %s = %.9g, |diff| %.3g > %.3g", #a, a_, #b, b_,             \
                     fabs(a_ - b_), t_);                                                     \
        }                                                                                    \
    } while (0)

#endif
