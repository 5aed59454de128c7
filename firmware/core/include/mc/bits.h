/* A float32 as its IEEE-754 bits and back, for records and blocks that cross to another
 * machine as 32-bit words (mc/store.h, mc/monitor.h). memcpy: no aliasing, compiles to a move. */
#ifndef MC_BITS_H
#define MC_BITS_H
#include <stdint.h>
#include <string.h>

static inline uint32_t mc_f32_bits(float x)
{
    uint32_t w;
    memcpy(&w, &x, sizeof w);
    return w;
}

static inline float mc_bits_f32(uint32_t w)
{
    float x;
    memcpy(&x, &w, sizeof x);
    return x;
}

#endif
