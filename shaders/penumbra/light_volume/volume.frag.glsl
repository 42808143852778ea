// penumbra — the light volume's fragment stage (billeter2010: "add and subtract", clamped to the
// scene's depth). Each fragment is one crossing of its pixel's ray with the closed, outward volume:
// entering through a front face (-1) or leaving through a back face (+1) at distance t. Crossings in
// front of the scene add sign * A(t) to red; crossings behind it add only their sign to green, and
// the composite adds green * A(D) once: hidden crossings cancel in exact integer arithmetic, so a
// wall in front of the shafts leaves exactly the airlight without them. Additive blending into an
// RG32F target, no depth test, no culling, depth clamp on (volume faces nearer than the camera's
// near plane still count).
#include "penumbra/light_volume/render.glsl"

in vec3 penumbraLvRelative;
layout(location = 0) out vec2 penumbraLvAccumulate;

void main() {
    const ivec2 pixel = ivec2(gl_FragCoord.xy);
    const float sign_ = gl_FrontFacing ? -1.0 : 1.0;
    const float t = length(penumbraLvRelative);
    const float scene = penumbraLvSceneDistance(pixel);
    if (t < scene) penumbraLvAccumulate = vec2(sign_ * penumbraLvAirlight(penumbraLvPixelRay(pixel), t), 0.0);
    else penumbraLvAccumulate = vec2(0.0, sign_);
}
