// penumbra — the caster-position hook of the hard-shadow light pass (light_pass.vert.glsl).
//
// Hook: vec3 penumbraAfhCasterPosition() — the position of the current caster vertex, in the
// frame the view samples and the light use (world, or camera/light-relative far from the
// origin). This default reads vertex attribute 0 (vec3). To draw skinned, instanced or packed
// casters without forking the entry shader, replace this file in the ShaderLibrary you give the
// pipeline (library.add("penumbra/alias_free_hard/caster_position.glsl", your_text)): declare your
// inputs (attributes, SSBOs with bindings of your choice, gl_VertexID / gl_InstanceID pulls) and
// define the function. The light pass only needs positions: no normals, no UVs.
#ifndef PENUMBRA_ALIAS_FREE_HARD_CASTER_POSITION_GLSL
#define PENUMBRA_ALIAS_FREE_HARD_CASTER_POSITION_GLSL

layout(location = 0) in vec3 penumbraAfhInPosition;

vec3 penumbraAfhCasterPosition() { return penumbraAfhInPosition; }

#endif
