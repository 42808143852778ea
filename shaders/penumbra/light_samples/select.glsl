// penumbra — per-pixel light-sample set and rotation (laine2005 §3.4: K sets turn banding into
// noise; sintorn2008 §4.2: a per-pixel rotation about the light's symmetry axis and a temporal
// sequence). GLSL twin of penumbra::lightSampleSet / lightSampleRotationHash /
// lightSampleRotationTurnsFloat (include/penumbra/light_samples.hpp): the same uint arithmetic,
// bit for bit on any conformant driver (tests/light_samples_gl_test.cpp).
//
//   uint  penumbraLightSampleSet(uvec2 pixel, uint frame, uint sets)
//         (x + c y + frame) mod sets, c = penumbraLightSampleSetStride(sets): the 8 neighbours of a
//         pixel use other sets whenever sets >= 4; a pixel takes every set in `sets` frames.
//   uint  penumbraLightSampleRotationHash(uvec2 pixel, uint frame, uint seed)
//   float penumbraLightSampleRotationTurns(uvec2 pixel, uint frame, uint seed)
//         the hash's top 24 bits * 2^-24: in [0, 1), exact in float.
// A snippet: no version line, no bindings, no hooks.
#ifndef PENUMBRA_LIGHT_SAMPLES_SELECT_GLSL
#define PENUMBRA_LIGHT_SAMPLES_SELECT_GLSL

#include "penumbra/light_samples/light_samples_shared.h"

uint penumbraLightSampleSetStride(uint sets) {
    if (sets < 4u) return 1u;
    uint c = ((sets * uint(PENUMBRA_LIGHT_SAMPLES_STRIDE_NUMERATOR)) >> 16) | 1u;
    if (c > sets - 2u) c = sets - 2u;
    if (c < 2u) c = 2u;
    return c;
}

uint penumbraLightSampleSet(uvec2 pixel, uint frame, uint sets) {
    if (sets <= 1u) return 0u;
    uint c = penumbraLightSampleSetStride(sets);
    return ((pixel.x % sets) + c * (pixel.y % sets) + (frame % sets)) % sets;
}

uint penumbraLightSampleHash32(uint v) {
    v ^= v >> 16;
    v *= PENUMBRA_LIGHT_SAMPLES_HASH_M1;
    v ^= v >> 15;
    v *= PENUMBRA_LIGHT_SAMPLES_HASH_M2;
    v ^= v >> 16;
    return v;
}

uint penumbraLightSampleRotationHash(uvec2 pixel, uint frame, uint seed) {
    uint h = penumbraLightSampleHash32(seed + PENUMBRA_LIGHT_SAMPLES_HASH_SEED_OFFSET);
    return penumbraLightSampleHash32(pixel.x + penumbraLightSampleHash32(pixel.y + penumbraLightSampleHash32(frame + h)));
}

float penumbraLightSampleRotationTurns(uvec2 pixel, uint frame, uint seed) {
    return float(penumbraLightSampleRotationHash(pixel, frame, seed) >> 8u) * (1.0 / 16777216.0);
}

#endif
