// Test-only entry (tests/light_samples_gl_test.cpp): runs penumbra/light_samples/select.glsl over
// a grid of pixels. Invocation (x, y) of frame z writes four words at 4 * ((z * height + y) * width + x):
//   penumbraLightSampleSet(pixel, frame, sets), penumbraLightSampleRotationHash(pixel, frame, seed),
//   floatBitsToUint(penumbraLightSampleRotationTurns(pixel, frame, seed)), penumbraLightSampleSetStride(sets).
#include "penumbra/light_samples/select.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, binding = 0) writeonly buffer LightSamplesSelectTestResults { uint lightSamplesSelectTestResults[]; };

layout(location = 0) uniform uvec2 lightSamplesSelectTestSize;   // width, height
layout(location = 1) uniform uint lightSamplesSelectTestSets;
layout(location = 2) uniform uint lightSamplesSelectTestSeed;
layout(location = 3) uniform uvec2 lightSamplesSelectTestOrigin;  // added to the pixel (large coordinates)
layout(location = 4) uniform uint lightSamplesSelectTestFrame0;   // frame of z = 0

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= lightSamplesSelectTestSize.x || id.y >= lightSamplesSelectTestSize.y) return;
    uvec2 pixel = id.xy + lightSamplesSelectTestOrigin;
    uint frame = lightSamplesSelectTestFrame0 + id.z;
    uint at = 4u * ((id.z * lightSamplesSelectTestSize.y + id.y) * lightSamplesSelectTestSize.x + id.x);
    lightSamplesSelectTestResults[at + 0u] = penumbraLightSampleSet(pixel, frame, lightSamplesSelectTestSets);
    lightSamplesSelectTestResults[at + 1u] = penumbraLightSampleRotationHash(pixel, frame, lightSamplesSelectTestSeed);
    lightSamplesSelectTestResults[at + 2u] = floatBitsToUint(penumbraLightSampleRotationTurns(pixel, frame, lightSamplesSelectTestSeed));
    lightSamplesSelectTestResults[at + 3u] = penumbraLightSampleSetStride(lightSamplesSelectTestSets);
}
