/* Shared value types of the firmware core. SI units: A, V, Wb, H, rad, rad/s (electrical). */
#ifndef MC_TYPES_H
#define MC_TYPES_H
#include <stdbool.h>
#include <stdint.h>

typedef struct { float a, b, c; } mc_abc_t;          /* phase quantities                 */
typedef struct { float alpha, beta; } mc_ab_t;       /* stationary frame (2.4)           */
typedef struct { float d, q; } mc_dq_t;              /* rotor / estimated frame (2.5)    */
typedef struct { float s, c; } mc_sincos_t;          /* sin and cos of one angle         */

#define MC_PI      3.14159265358979f
#define MC_2PI     6.28318530717959f
#define MC_SQRT3   1.73205080756888f
#define MC_1_SQRT3 0.57735026918963f

#endif
