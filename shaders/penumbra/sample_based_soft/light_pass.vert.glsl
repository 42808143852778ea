// penumbra — sample-based soft shadows, light pass, vertex stage: the caster's world position
// (through the hard pipeline's hook penumbraAfhCasterPosition(), penumbra/alias_free_hard/
// caster_position.glsl: attribute 0 by default; replace that file in your ShaderLibrary for
// skinning, instancing or packed positions) passed to the geometry stage in gl_Position.xyz
// (w = 1): the influence region is built from world positions, not from a projection.
#include "penumbra/alias_free_hard/caster_position.glsl"

void main() {
    const vec3 p = penumbraAfhCasterPosition();
    gl_Position = vec4(p, 1.0);
}
