/* The angle-source registry: the descriptors listed in MC_ANGLE_SOURCES (mc/angle_source.h), in
 * the order of control.angle_source's choices. */
#include "mc/angle_source.h"
#include <stddef.h>

static const mc_angle_src_desc_t *const sources[MC_ANGLE_SRC_COUNT] = {
#define MC_X(name) &mc_angle_src_##name,
    MC_ANGLE_SOURCES(MC_X)
#undef MC_X
};

const mc_angle_src_desc_t *mc_angle_src_get(int kind)
{
    return kind >= 0 && kind < (int)MC_ANGLE_SRC_COUNT ? sources[kind] : NULL;
}
