// penumbra — bent-normal shading (sintorn2008 §4.3, Fig. 8): the GLSL twin of
// include/penumbra/bent_normals.hpp's bentLight / bentShade / bentDirect (same float operations,
// `precise`). A snippet: no version line, no bindings, no main.
//
// Hooks the integrator defines before including it (for penumbraBentLight only):
//   PENUMBRA_BENT_OFFSET(v)       -> uint: BentNormalMesh::offsets[v]
//   PENUMBRA_BENT_FACE(i)         -> uint: BentNormalMesh::faces[i]
//   PENUMBRA_BENT_FACE_NORMAL(f)  -> vec3: BentNormalMesh::face_normals[f].xyz
// Use: per bent vertex l_bend = penumbraBentLight(bent vertex, position, light centre, light radius)
// (or read bent_normals.comp.glsl's output), draw with BentNormalMesh::indices so each corner gets
// its smooth group's value, interpolate it, then per fragment
// direct = penumbraBentDirect(l_bend, your diffuse term, 3.0) in place of max(diffuse, 0).
#ifndef PENUMBRA_BENT_NORMALS_GLSL
#define PENUMBRA_BENT_NORMALS_GLSL

#ifdef PENUMBRA_BENT_FACE_NORMAL
#if !defined(PENUMBRA_BENT_OFFSET)
#error "bent_normals.glsl: define PENUMBRA_BENT_OFFSET(v) (BentNormalMesh::offsets[v])"
#endif
#if !defined(PENUMBRA_BENT_FACE)
#error "bent_normals.glsl: define PENUMBRA_BENT_FACE(i) (BentNormalMesh::faces[i])"
#endif

float penumbraBentLight(uint vertex, vec3 position, vec3 centre, float radius) {
    const uint first = PENUMBRA_BENT_OFFSET(vertex), last = PENUMBRA_BENT_OFFSET(vertex + 1u);
    if (first == last) return 1.0;
    precise vec3 to_light = centre - position;
    precise float distance2 = (to_light.x * to_light.x + to_light.y * to_light.y) + to_light.z * to_light.z;
    const float distance = sqrt(distance2);
    if (!(distance > radius)) return -1.0;
    const vec3 l = to_light / distance;
    const float sin_t = radius / distance;
    precise float sin_t2 = sin_t * sin_t;
    const float cos_t = sqrt(max(0.0, 1.0 - sin_t2));
    float least = 1.0;
    for (uint i = first; i < last; ++i) {
        const vec3 n = PENUMBRA_BENT_FACE_NORMAL(PENUMBRA_BENT_FACE(i));
        precise float d = (l.x * n.x + l.y * n.y) + l.z * n.z;
        float value = d;
        if (radius > 0.0) {
            precise float d2 = d * d;
            const float sin_a = sqrt(max(0.0, 1.0 - d2));
            precise float bent = d * cos_t - sin_a * sin_t;
            value = d <= -cos_t ? -1.0 : bent;
        }
        least = min(least, value);
    }
    return least;
}
#endif

// alpha = clamp(c l_bend, 0, 1); alpha l_f + (1 - alpha) l_bend.
float penumbraBentShade(float l_bend, float l_f, float sharpness) {
    precise float scaled = sharpness * l_bend;
    const float alpha = clamp(scaled, 0.0, 1.0);
    precise float shade = alpha * l_f + (1.0 - alpha) * l_bend;
    return shade;
}

// The direct light factor: max(shade, 0); exactly 0 on light-back-facing triangles.
float penumbraBentDirect(float l_bend, float l_f, float sharpness) {
    return max(penumbraBentShade(l_bend, l_f, sharpness), 0.0);
}

#endif
