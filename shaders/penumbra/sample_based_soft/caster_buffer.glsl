// penumbra — the caster hook of the compute light pass (light_pass_setup.comp.glsl), the compute
// twin of penumbra/alias_free_hard/caster_position.glsl: where a caster triangle's world vertices
// come from when the casters are buffers (penumbra::CasterBuffer).
//
// Hook: bool penumbraSbsCasterTriangle(uint t, out vec3 v[3]) — triangle t (0 .. triangles - 1 of
// the range being set up) in the frame the view samples and the light use; false: the triangle
// names a vertex past the positions (it casts nothing; the pass counts it). This default reads 3
// floats per vertex at a stride from the positions buffer, through 32-bit indices when the range
// has them. Replace this file in the ShaderLibrary you give the pipeline for packed, skinned or
// instanced positions (declare your own buffers, with bindings of your choice).
// Uniforms (set by the pipeline per range): penumbraSbsCasterRange = (first triangle of this
// dispatch, triangles in it, stride in floats, 1 = indexed), penumbraSbsCasterFloats = the floats
// the positions range holds.
#ifndef PENUMBRA_SBS_CASTER_BUFFER_GLSL
#define PENUMBRA_SBS_CASTER_BUFFER_GLSL

layout(std430, binding = PENUMBRA_SBS_CASTER_POSITIONS_BINDING) readonly buffer PenumbraSbsCasterPositions {
    float penumbraSbsCasterPositions[];
};
layout(std430, binding = PENUMBRA_SBS_CASTER_INDICES_BINDING) readonly buffer PenumbraSbsCasterIndices {
    uint penumbraSbsCasterIndices[];
};
layout(location = 0) uniform uvec4 penumbraSbsCasterRange;
layout(location = 1) uniform uint penumbraSbsCasterFloats;

bool penumbraSbsCasterTriangle(uint t, out vec3 v[3]) {
    const uint stride = penumbraSbsCasterRange.z;
    bool inside = true;
    for (uint i = 0u; i < 3u; ++i) {
        const uint corner = 3u * t + i;
        const uint vertex = penumbraSbsCasterRange.w != 0u ? penumbraSbsCasterIndices[corner] : corner;
        // In double (exact below 2^53): vertex * stride may pass 2^32 for a hostile index.
        const bool fits = double(vertex) * double(stride) + 3.0LF <= double(penumbraSbsCasterFloats);
        const uint base = fits ? vertex * stride : 0u;
        v[i] = fits ? vec3(penumbraSbsCasterPositions[base], penumbraSbsCasterPositions[base + 1u],
                           penumbraSbsCasterPositions[base + 2u])
                    : vec3(0.0);
        inside = inside && fits;
    }
    return inside;
}

#endif
