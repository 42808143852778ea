// penumbra — shadow-edge stencil, galoppo2010's Chebyshev stencil (Listing 1.6.1) over the moment
// map: per pixel the level whose texels are at least its footprint's light-space extent, the mean
// moments of the <= 2x2 texels the footprint's box touches, and Chebyshev's one-tailed bounds;
// unflagged when one says fully lit or fully shadowed with probability >= 1 - threshold (or, with
// moments.y, shadowed by the inner-coverage proof). Reads the facing word the footprints pass left.
// The twin: chebyshevEdgeStencilCpu. Writes PENUMBRA_AA_FLAG or 0. One invocation per pixel.
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h"
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil.glsl"

layout(local_size_x = PENUMBRA_AA_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_AA_BINDING_PARAMS) uniform PenumbraAaParamsBlock { PenumbraAaParams penumbraAaParams; };
layout(std430, binding = PENUMBRA_AA_BINDING_CENTRES) readonly buffer PenumbraAaCentres { vec4 penumbraAaCentres[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_SUB_SAMPLES) readonly buffer PenumbraAaSubSamples { vec4 penumbraAaSubSamples[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_STENCIL) buffer PenumbraAaStencil { uint penumbraAaStencil[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_MOMENTS) readonly buffer PenumbraAaMoments { vec2 penumbraAaMoments[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_COVERS) readonly buffer PenumbraAaCovers { float penumbraAaCovers[]; };

uint penumbraAaLevelWidth(uint l) { return max(1u, penumbraAaParams.grid.x >> l); }
uint penumbraAaLevelHeight(uint l) { return max(1u, penumbraAaParams.grid.y >> l); }

void main() {
    uint width = penumbraAaParams.view.x, height = penumbraAaParams.view.y, n = penumbraAaParams.view.z;
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (i >= width * height) return;
    uint word = penumbraAaStencil[i];
    if ((word & PENUMBRA_AA_ACTIVE) == 0u) {  // no surface (0), all back-facing (0), mixed facing (FLAG)
        penumbraAaStencil[i] = word & PENUMBRA_AA_FLAG;
        return;
    }
    uint gw = penumbraAaParams.grid.x, gh = penumbraAaParams.grid.y, levels = penumbraAaParams.moments.x;
    bool perspective = penumbraAaParams.moments.z != 0u;
    dvec4 m0 = penumbraAaParams.light_view_projection[0], m1 = penumbraAaParams.light_view_projection[1];
    dvec4 m2 = penumbraAaParams.light_view_projection[2], m3 = penumbraAaParams.light_view_projection[3];
    dvec2 lo = dvec2(1e300lf), hi = dvec2(-1e300lf);
    double t_min = 1e300lf, t_max = -1e300lf;
    bool inside = true;
    for (uint k = 0u; k <= n && inside; ++k) {
        vec4 p = k == 0u ? penumbraAaCentres[i] : penumbraAaSubSamples[i * n + k - 1u];
        dvec4 c = penumbraAaTransform(m0, m1, m2, m3, dvec4(dvec3(p.xyz), 1.0lf));
        if (!(c.w > 0.0lf)) {
            inside = false;
            break;
        }
        dvec2 g = dvec2(penumbraAaGrid(c.x, c.w, gw), penumbraAaGrid(c.y, c.w, gh));
        if (!(g.x >= 0.0lf && g.x <= double(gw) && g.y >= 0.0lf && g.y <= double(gh))) inside = false;
        lo = min(lo, g);
        hi = max(hi, g);
        double d = penumbraAaLightDepth(c, perspective);
        t_min = min(t_min, d);
        t_max = max(t_max, d);
    }
    if (!inside) {
        penumbraAaStencil[i] = PENUMBRA_AA_FLAG;
        return;
    }
    precise double extent = max(hi.x - lo.x, hi.y - lo.y);
    uint level = 0u, offset = 0u;
    double span = 1.0lf;
    while (span < extent && level + 1u < levels) {
        offset += penumbraAaLevelWidth(level) * penumbraAaLevelHeight(level);
        span = span * 2.0lf;
        ++level;
    }
    uint lw = penumbraAaLevelWidth(level), lh = penumbraAaLevelHeight(level);
    int x0 = clamp(int(floor(lo.x / span)), 0, int(lw) - 1), x1 = clamp(int(floor(hi.x / span)), 0, int(lw) - 1);
    int y0 = clamp(int(floor(lo.y / span)), 0, int(lh) - 1), y1 = clamp(int(floor(hi.y / span)), 0, int(lh) - 1);
    double sum_x = 0.0lf, sum_y = 0.0lf;
    float covered = uintBitsToFloat(0xff800000u);  // -inf
    int count = 0;
    for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
            vec2 m = penumbraAaMoments[offset + uint(y) * lw + uint(x)];
            precise double nx = sum_x + double(m.x);
            precise double ny = sum_y + double(m.y);
            sum_x = nx;
            sum_y = ny;
            covered = max(covered, penumbraAaCovers[offset + uint(y) * lw + uint(x)]);
            ++count;
        }
    }
    precise double mu = sum_x / double(count);
    precise double second = sum_y / double(count);
    precise double raw_var = second - mu * mu;
    double var = max(double(penumbraAaParams.chebyshev.z), raw_var);
    double threshold = double(penumbraAaParams.chebyshev.x);
    bool decided = false;
    if (penumbraAaParams.moments.y != 0u) {
        precise double bound = t_min - 1e-6lf * abs(t_min);
        decided = double(covered) < bound;
    } else if (t_min > mu) {
        precise double gap = t_min - mu;
        precise double p_max = var / (var + gap * gap);
        decided = p_max < threshold;
    }
    precise double spread = ((t_max - t_min) * (2.0lf * span)) / max(extent, 1.0lf / 1048576.0lf);
    precise double t_lit = t_min - double(penumbraAaParams.chebyshev.y) * spread;
    if (!decided && t_lit < mu) {
        precise double gap = mu - t_lit;
        precise double p_max = var / (var + gap * gap);
        decided = p_max < threshold;
    }
    penumbraAaStencil[i] = decided ? 0u : PENUMBRA_AA_FLAG;
}
