/* Shared includes and helpers of the core unit tests. */
#ifndef CORE_TEST_H
#define CORE_TEST_H
#include "../mc_test.h"
#endif
