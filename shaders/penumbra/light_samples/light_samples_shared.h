// penumbra — light-sample constants shared by C++ (include/penumbra/light_samples.hpp) and GLSL
// (select.glsl). Valid as both. The hash multipliers carry a `u` suffix (valid C++ and GLSL);
// the other values are plain decimals so they also work in #if lines.
#ifndef PENUMBRA_LIGHT_SAMPLES_SHARED_H
#define PENUMBRA_LIGHT_SAMPLES_SHARED_H

// LightSampleOptions ranges: N samples per set (a multiple of 32, so a set is whole 32-bit mask
// words for the LUT of sintorn2008 §4.2) and K distinct sets (laine2005 §3.4).
#define PENUMBRA_LIGHT_SAMPLES_MIN_COUNT 32
#define PENUMBRA_LIGHT_SAMPLES_MAX_COUNT 1024
#define PENUMBRA_LIGHT_SAMPLES_COUNT_MULTIPLE 32
#define PENUMBRA_LIGHT_SAMPLES_MAX_SETS 64

// The per-pixel set pattern (x + stride * y + frame) mod sets: stride = floor(sets * 40503 / 2^16)
// (sets / golden ratio), made odd, clamped to [2, sets - 2] (sets >= 4).
#define PENUMBRA_LIGHT_SAMPLES_STRIDE_NUMERATOR 40503

// The rotation hash: Chris Wellons' "lowbias32" integer finaliser, nested over seed, frame, y, x;
// the seed is offset first (lowbias32(0) = 0 would leave pixel (0, 0) of frame 0 unrotated).
#define PENUMBRA_LIGHT_SAMPLES_HASH_M1 0x7feb352du
#define PENUMBRA_LIGHT_SAMPLES_HASH_M2 0x846ca68bu
#define PENUMBRA_LIGHT_SAMPLES_HASH_SEED_OFFSET 0x9e3779b9u

#endif
