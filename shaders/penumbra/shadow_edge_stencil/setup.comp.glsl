// penumbra — shadow-edge stencil, passes 2 and 4: bins each active pixel's footprint (its centre
// and N sub-samples) into every light texel its box touches, 1/64 texel of slack per side (the twin:
// provableEdgeStencilCpu). PENUMBRA_AA_PASS 0: box, bounding sphere, counts per texel (a point
// outside the light's frustum, or a box over limits.x texels: FLAG — multi-sampling is always
// safe); 1, after the exclusive scan of the counts: scatter pixel ids to offsets[texel] + cursor (a
// texel holding more than limits.y footprints, or an entry over the list capacity, flags the pixel
// instead). One invocation per pixel.
// penumbra-permutation: PENUMBRA_AA_PASS=0
// penumbra-permutation: PENUMBRA_AA_PASS=1
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h"
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil.glsl"

#ifndef PENUMBRA_AA_PASS
#error penumbra/shadow_edge_stencil/setup.comp.glsl needs PENUMBRA_AA_PASS (0 count, 1 scatter)
#endif

layout(local_size_x = PENUMBRA_AA_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_AA_BINDING_PARAMS) uniform PenumbraAaParamsBlock { PenumbraAaParams penumbraAaParams; };
layout(std430, binding = PENUMBRA_AA_BINDING_CENTRES) readonly buffer PenumbraAaCentres { vec4 penumbraAaCentres[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_STATUS) buffer PenumbraAaStatus { uint penumbraAaStatus[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_SUB_SAMPLES) readonly buffer PenumbraAaSubSamples { vec4 penumbraAaSubSamples[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_STENCIL) buffer PenumbraAaStencil { uint penumbraAaStencil[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_FOOTPRINTS) buffer PenumbraAaFootprints { PenumbraAaFootprint penumbraAaFootprints[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_COUNTS) buffer PenumbraAaCounts { uint penumbraAaCounts[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_CURSOR) buffer PenumbraAaCursor { uint penumbraAaCursor[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_LIST) writeonly buffer PenumbraAaList { uint penumbraAaList[]; };

void main() {
    uint width = penumbraAaParams.view.x, height = penumbraAaParams.view.y, n = penumbraAaParams.view.z;
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (i >= width * height) return;
    if ((penumbraAaStencil[i] & PENUMBRA_AA_ACTIVE) == 0u) return;
    uint gw = penumbraAaParams.grid.x, gh = penumbraAaParams.grid.y;
#if PENUMBRA_AA_PASS == 0
    dvec4 m0 = penumbraAaParams.light_view_projection[0], m1 = penumbraAaParams.light_view_projection[1];
    dvec4 m2 = penumbraAaParams.light_view_projection[2], m3 = penumbraAaParams.light_view_projection[3];
    dvec3 c = dvec3(penumbraAaCentres[i].xyz);
    double radius = 0.0lf;
    dvec2 lo = dvec2(1e300lf), hi = dvec2(-1e300lf);
    bool inside = true;
    for (uint k = 0u; k <= n && inside; ++k) {
        dvec3 p = dvec3(k == 0u ? penumbraAaCentres[i].xyz : penumbraAaSubSamples[i * n + k - 1u].xyz);
        precise dvec3 pc = p - c;
        radius = max(radius, penumbraAaLength(pc));
        dvec4 clip = penumbraAaTransform(m0, m1, m2, m3, dvec4(p, 1.0lf));
        if (!(clip.w > 0.0lf)) {
            inside = false;
            break;
        }
        dvec2 g = dvec2(penumbraAaGrid(clip.x, clip.w, gw), penumbraAaGrid(clip.y, clip.w, gh));
        if (!(g.x >= 0.0lf && g.x <= double(gw) && g.y >= 0.0lf && g.y <= double(gh))) {
            inside = false;
            break;
        }
        lo = min(lo, g);
        hi = max(hi, g);
    }
    // 1/64 texel of slack (kAaBoxSlack): the casters' hulls come from float clip coordinates.
    ivec4 box = ivec4(max(0, int(floor(lo.x - 0.015625lf))), max(0, int(floor(lo.y - 0.015625lf))),
                      min(int(gw) - 1, int(floor(hi.x + 0.015625lf))), min(int(gh) - 1, int(floor(hi.y + 0.015625lf))));
    uint texels = inside ? uint(box.z - box.x + 1) * uint(box.w - box.y + 1) : 0u;
    if (!inside || texels > penumbraAaParams.limits.x) {
        penumbraAaStencil[i] = PENUMBRA_AA_FLAG;
        return;
    }
    penumbraAaFootprints[i].sphere = dvec4(c, radius);
    penumbraAaFootprints[i].box = box;
    for (int y = box.y; y <= box.w; ++y)
        for (int x = box.x; x <= box.z; ++x) atomicAdd(penumbraAaCounts[uint(y) * gw + uint(x)], 1u);
    atomicAdd(penumbraAaStatus[PENUMBRA_AA_STATUS_LIST_ENTRIES], texels);
#else
    ivec4 box = penumbraAaFootprints[i].box;
    uint capacity = penumbraAaParams.grid.z, max_list = penumbraAaParams.limits.y;
    bool flag = false;
    for (int y = box.y; y <= box.w; ++y) {
        for (int x = box.x; x <= box.z; ++x) {
            uint t = uint(y) * gw + uint(x);
            uint begin = penumbraAaCounts[t], count = penumbraAaCounts[t + 1u] - begin;
            if (count > max_list) {
                flag = true;
                continue;
            }
            uint slot = begin + atomicAdd(penumbraAaCursor[t], 1u);
            if (slot < capacity) {
                penumbraAaList[slot] = i;
            } else {
                atomicAdd(penumbraAaStatus[PENUMBRA_AA_STATUS_LIST_OVERFLOW], 1u);
                flag = true;
            }
        }
    }
    // Flagged pixels stay in the lists they entered (harmless: their classification is ignored).
    if (flag) atomicOr(penumbraAaStencil[i], PENUMBRA_AA_FLAG);
#endif
}
