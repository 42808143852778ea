// penumbra — light-volume lattice depths (billeter2010; the twin of lightVolumeCornerDepths): corner
// (i, j) of the (R + 1)^2 lattice from the shadow map, separably (x in every texel row, then y), the
// mean of the two texels around it or on the border the linear extrapolation of the nearest two,
// clamped to [0, 1]; every operation rounded alone (precise), in the host's order. One invocation per
// corner.
#include "penumbra/light_volume/light_volume_shared.h"
#include "penumbra/common/dispatch.glsl"

layout(local_size_x = PENUMBRA_LV_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_LV_BINDING_PARAMS) uniform PenumbraLvParamsBlock { PenumbraLightVolumeParams penumbraLvParams; };
layout(std430, binding = PENUMBRA_LV_BINDING_CORNERS) writeonly buffer PenumbraLvCorners { float penumbraLvCorners[]; };
layout(binding = PENUMBRA_LV_DEPTH_UNIT) uniform sampler2D penumbraLvDepth;

float penumbraLvLerp(float near_value, float far_value, bool border) {
    precise float value;
    if (border) {
        precise float step = (near_value - far_value) * 0.5;
        value = near_value + step;
    } else {
        value = (near_value + far_value) * 0.5;
    }
    return value;
}

float penumbraLvAlongX(uint i, uint y) {
    const uint r = penumbraLvParams.size.x;
    const int row = int(y);
    if (i == 0u) return penumbraLvLerp(texelFetch(penumbraLvDepth, ivec2(0, row), 0).r, texelFetch(penumbraLvDepth, ivec2(1, row), 0).r, true);
    if (i == r)
        return penumbraLvLerp(texelFetch(penumbraLvDepth, ivec2(int(r) - 1, row), 0).r,
                              texelFetch(penumbraLvDepth, ivec2(int(r) - 2, row), 0).r, true);
    return penumbraLvLerp(texelFetch(penumbraLvDepth, ivec2(int(i) - 1, row), 0).r, texelFetch(penumbraLvDepth, ivec2(int(i), row), 0).r,
                          false);
}

void main() {
    const uint r = penumbraLvParams.size.x, n = r + 1u;
    const uint index = penumbraLinearGroup() * PENUMBRA_LV_GROUP_SIZE + gl_LocalInvocationID.x;
    if (index >= n * n) return;
    const uint i = index % n, j = index / n;
    float value;
    if (j == 0u) value = penumbraLvLerp(penumbraLvAlongX(i, 0u), penumbraLvAlongX(i, 1u), true);
    else if (j == r) value = penumbraLvLerp(penumbraLvAlongX(i, r - 1u), penumbraLvAlongX(i, r - 2u), true);
    else value = penumbraLvLerp(penumbraLvAlongX(i, j - 1u), penumbraLvAlongX(i, j), false);
    penumbraLvCorners[index] = min(1.0, max(0.0, value));
}
