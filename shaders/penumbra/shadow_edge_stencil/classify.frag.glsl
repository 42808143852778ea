// penumbra — shadow-edge stencil, pass 5, fragment stage: one fragment per (caster triangle, light
// texel its conservative hull touches) walks the texel's footprint list and classifies each pixel's
// K = N + 1 points against the triangle (the twin: provableEdgeStencilCpu): the bounding-sphere
// test against the triangle's shadow volume decides most pairs; an undecided pair runs the hard
// pipeline's exact test (blocker_test.glsl: filtered, the decisions of double) on every point.
// Blocks all: COVERED; some but not all: SPLIT (atomicOr: the result is independent of the order,
// and of how often a pair is seen). No colour output: an attachment-less W x H framebuffer.
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h"
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil.glsl"
#define PENUMBRA_AFH_EXACT 1
#include "penumbra/alias_free_hard/blocker_test.glsl"

layout(std140, binding = PENUMBRA_AA_BINDING_PARAMS) uniform PenumbraAaParamsBlock { PenumbraAaParams penumbraAaParams; };
layout(std430, binding = PENUMBRA_AA_BINDING_CENTRES) readonly buffer PenumbraAaCentres { vec4 penumbraAaCentres[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_STATUS) buffer PenumbraAaStatus { uint penumbraAaStatus[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_SUB_SAMPLES) readonly buffer PenumbraAaSubSamples { vec4 penumbraAaSubSamples[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_STENCIL) coherent buffer PenumbraAaStencil { uint penumbraAaStencil[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_FOOTPRINTS) readonly buffer PenumbraAaFootprints { PenumbraAaFootprint penumbraAaFootprints[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_COUNTS) readonly buffer PenumbraAaOffsets { uint penumbraAaOffsets[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_LIST) readonly buffer PenumbraAaList { uint penumbraAaList[]; };

layout(location = 0) flat in vec3 penumbraAaVertex0;
layout(location = 1) flat in vec3 penumbraAaVertex1;
layout(location = 2) flat in vec3 penumbraAaVertex2;

void main() {
    uint gw = penumbraAaParams.grid.x, gh = penumbraAaParams.grid.y, n = penumbraAaParams.view.z;
    uint x = uint(gl_FragCoord.x), y = uint(gl_FragCoord.y);
    if (x >= gw || y >= gh) return;
    uint t = y * gw + x;
    uint begin = penumbraAaOffsets[t], end = min(penumbraAaOffsets[t + 1u], penumbraAaParams.grid.z);
    if (begin >= end || end - begin > penumbraAaParams.limits.y) return;  // over-long lists: their pixels are flagged
    vec4 light = penumbraAaParams.light;
    double reach = penumbraAaParams.numbers.y, eps = penumbraAaParams.numbers.x;
    dvec3 a = dvec3(penumbraAaVertex0), b = dvec3(penumbraAaVertex1), c = dvec3(penumbraAaVertex2);
    PenumbraAaVolume volume = penumbraAaShadowVolume(a, b, c, light, reach);
    if (volume.blocks_nothing) return;
    uint pairs = 0u, exact = 0u;
    for (uint e = begin; e < end; ++e) {
        uint i = penumbraAaList[e];
        if ((penumbraAaStencil[i] & (PENUMBRA_AA_COVERED | PENUMBRA_AA_FLAG)) != 0u) continue;
        ++pairs;
        dvec4 sphere = penumbraAaFootprints[i].sphere;
        double margin = penumbraAaSphereMargin(a, b, c, sphere.xyz, sphere.w, light, reach, eps);
        int cls = penumbraAaSphereClass(volume, sphere.xyz, margin, light);
        if (cls < 0) continue;
        if (cls > 0) {
            atomicOr(penumbraAaStencil[i], PENUMBRA_AA_COVERED);
            continue;
        }
        uint blocked = 0u;
        for (uint k = 0u; k <= n; ++k) {
            vec3 p = k == 0u ? penumbraAaCentres[i].xyz : penumbraAaSubSamples[i * n + k - 1u].xyz;
            blocked += penumbraAfhBlocksLight(penumbraAaVertex0, penumbraAaVertex1, penumbraAaVertex2, p, light, float(reach), eps,
                                              0.0lf, penumbraAaParams.numbers.w) ? 1u : 0u;
        }
        exact += n + 1u;
        if (blocked == n + 1u) atomicOr(penumbraAaStencil[i], PENUMBRA_AA_COVERED);
        else if (blocked != 0u) atomicOr(penumbraAaStencil[i], PENUMBRA_AA_SPLIT);
    }
    if (pairs > 0u) atomicAdd(penumbraAaStatus[PENUMBRA_AA_STATUS_PAIRS], pairs);
    if (exact > 0u) atomicAdd(penumbraAaStatus[PENUMBRA_AA_STATUS_EXACT], exact);
}
