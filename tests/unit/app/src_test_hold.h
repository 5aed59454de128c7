/* The test-only angle source "test_hold" (src_test_hold.c): registered by a test build through
 * MC_ANGLE_SOURCES_EXTRA (tests/unit/app/CMakeLists.txt). */
#ifndef SRC_TEST_HOLD_H
#define SRC_TEST_HOLD_H

/* Read by its build: the ramp speed [rad/s el] (0: hold); a build refuses one above
 * protection.overspeed_rpm. */
extern float test_hold_omega;
/* Added to the raw speed it reports (diag) [rad/s el]: a raw estimate that disagrees with the
 * output, for the loss-of-lock checks. */
extern float test_hold_raw_offset;
/* The input of its last step, and its steps so far (a test may zero it). */
#include <stdint.h>
#include "mc/angle_source.h"
extern mc_angle_in_t test_hold_in;
extern uint32_t test_hold_steps;

#endif
