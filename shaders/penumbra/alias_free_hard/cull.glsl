// penumbra — the per-triangle culls of the hard-shadow light pass, one function for both light
// passes: the raster pass's geometry stage (light_pass.geom.glsl) and the compute pass's caster
// setup (light_pass_setup.comp.glsl). No hooks.
#ifndef PENUMBRA_AFH_CULL_GLSL
#define PENUMBRA_AFH_CULL_GLSL

#include "penumbra/alias_free_hard/degenerate.glsl"

#define PENUMBRA_AFH_CULL_NONE 0        // the triangle casts
#define PENUMBRA_AFH_CULL_DEGENERATE 1  // blocks nothing (the oracle's rule); not counted as culled
#define PENUMBRA_AFH_CULL_CLOSED 2      // a closed caster's cull (`flags`); counted as culled

// Which cull, if any, removes the triangle (a, b, c) for `light` (PenumbraAfhParams::light) and
// the draw's `flags` (PENUMBRA_AFH_FLAG_*). Everything in double: a triangle wrongly culled would
// be a missing blocker.
int penumbraAfhCull(vec3 a, vec3 b, vec3 c, vec4 light, uint flags) {
    // Degenerate casters block nothing (the oracle's rule, shared): culled once per triangle.
    if (penumbraAfhDegenerate(dvec3(a), dvec3(b), dvec3(c))) return PENUMBRA_AFH_CULL_DEGENERATE;
    const dvec3 da = dvec3(a), db = dvec3(b), dc = dvec3(c);
    const dvec3 to_light = light.w != 0.0 ? dvec3(light.xyz) - da : dvec3(light.xyz);
    if ((flags & PENUMBRA_AFH_FLAG_CLOSED) != 0u) {
        // §3.3: of a closed caster only the light-back-facing triangles cast. Edge-on triangles
        // (facing exactly 0) block nothing: the oracle's coplanar rule ignores them.
        precise double facing = dot(cross(db - da, dc - da), to_light);
        if (facing >= 0.0) return PENUMBRA_AFH_CULL_CLOSED;
    }
    if ((flags & PENUMBRA_AFH_FLAG_CLOSED_LIGHT_FACING) != 0u) {
        // light_facing_only: a closed caster's triangle with the light strictly behind its plane
        // is never the face a blocked segment leaves the solid through: culled (exact). The twin:
        // detail::afhFacesAway, step for step.
        dvec3 e0 = db - da, e1 = dc - da;
        precise dvec3 n = dvec3(e0.y * e1.z - e0.z * e1.y, e0.z * e1.x - e0.x * e1.z, e0.x * e1.y - e0.y * e1.x);
        precise double facing = (n.x * to_light.x + n.y * to_light.y) + n.z * to_light.z;
        precise double e00 = (e0.x * e0.x + e0.y * e0.y) + e0.z * e0.z;
        precise double e11 = (e1.x * e1.x + e1.y * e1.y) + e1.z * e1.z;
        precise double nn = (n.x * n.x + n.y * n.y) + n.z * n.z;
        precise double ll = (to_light.x * to_light.x + to_light.y * to_light.y) + to_light.z * to_light.z;
        precise double bound = (8.0LF * 1.1102230246251565404e-16LF * sqrt(e00) * sqrt(e11) +
                                8.0LF * 1.1102230246251565404e-16LF * sqrt(nn)) * sqrt(ll);
        if (facing < -bound * (1.0LF + 1e-9LF)) return PENUMBRA_AFH_CULL_CLOSED;
    }
    return PENUMBRA_AFH_CULL_NONE;
}

#endif
