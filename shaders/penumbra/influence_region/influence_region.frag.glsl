#version 450
// penumbra — fragment stage recording which light-grid texels each triangle's influence region
// covers (the tests' recorder; the soft-shadow light pass walks the texel's view-sample list here
// instead). Per triangle, PENUMBRA_INFLUENCE_COVERAGE_WORDS(W, H) uints at binding
// PENUMBRA_INFLUENCE_COVERAGE_BINDING: word 0 counts fragments, then one bit per texel
// (bit t % 32 of word 1 + t / 32, t = y W + x, window pixels relative to the viewport origin at
// uniform location 9). Uniform location 10: the grid size (W, H).
#include "penumbra/influence_region/influence_region_shared.h"

layout(location = 0) flat in uint penumbraInfluenceTriangle;
layout(location = 9) uniform ivec2 penumbraInfluenceViewportOrigin;
layout(location = 10) uniform uvec2 penumbraInfluenceGridSize;

layout(std430, binding = PENUMBRA_INFLUENCE_COVERAGE_BINDING) buffer PenumbraInfluenceCoverageBlock {
    uint penumbraInfluenceCoverage[];
};

void main() {
    uvec2 texel = uvec2(ivec2(floor(gl_FragCoord.xy)) - penumbraInfluenceViewportOrigin);
    uint words = 1u + (penumbraInfluenceGridSize.x * penumbraInfluenceGridSize.y + 31u) / 32u;
    uint base = penumbraInfluenceTriangle * words;
    atomicAdd(penumbraInfluenceCoverage[base], 1u);
    if (texel.x < penumbraInfluenceGridSize.x && texel.y < penumbraInfluenceGridSize.y) {
        uint t = texel.y * penumbraInfluenceGridSize.x + texel.x;
        atomicOr(penumbraInfluenceCoverage[base + 1u + t / 32u], 1u << (t % 32u));
    }
}
