// penumbra — light-sample LUT constants and the parameter block shared by C++
// (include/penumbra/light_lut.hpp, through penumbra/detail/shared.hpp) and GLSL (generate.comp.glsl,
// lookup.glsl). Valid as both; plain decimals so they also work in #if lines.
#ifndef PENUMBRA_LIGHT_LUT_SHARED_H
#define PENUMBRA_LIGHT_LUT_SHARED_H

#ifdef __cplusplus
namespace penumbra::shared {
#endif

// One table answers 128 light samples: one uvec4 (RGBA32UI texel) of bits per cell.
#define PENUMBRA_LUT_SAMPLES_PER_TABLE 128
#define PENUMBRA_LUT_MIN_RESOLUTION 16
#define PENUMBRA_LUT_MAX_RESOLUTION 256

// PenumbraLutParams::mapping: how a unit normal becomes two cell coordinates.
#define PENUMBRA_LUT_MAPPING_OCTAHEDRAL 0  // (u, v) in [-1, 1]^2 of the octahedral map
#define PENUMBRA_LUT_MAPPING_SPHERICAL 1   // (theta, phi): polar angle from local z, azimuth

// PenumbraLutParams::flags
#define PENUMBRA_LUT_FLAG_SYMMETRIC 1  // cells cover d in [0, 1]; (n, d < 0) reads (-n, -d), complemented
#define PENUMBRA_LUT_FLAG_CERTIFIED 2  // an uncertain mask follows the centre masks

// The exact side test's float filter (lookup.glsl penumbraLutExactBound, light_lut.hpp): the float
// value of dot(n, q) + w decides when its magnitude exceeds REL (|n|_1 + |w|) + ABS, else fp64 does.
#define PENUMBRA_LUT_EXACT_REL 1.0e-6   // > 2 gamma_4 (1 + 5u) = 9.54e-7, u = 2^-23: both paths' rounding
#define PENUMBRA_LUT_EXACT_ABS 1.0e-36  // > 2^-121 = 3.8e-37: flushed denormals (inputs and results)

// Default bindings of generate.comp.glsl (penumbra::LightLutBindings can move them).
#define PENUMBRA_LUT_BINDING_SAMPLES 0       // dvec4 per sample: local x, y, z, |q| (rounded up)
#define PENUMBRA_LUT_BINDING_NORMAL_CELLS 1  // dvec4 per normal cell: centre normal, rho
#define PENUMBRA_LUT_BINDING_DISTANCE_CELLS 2  // dvec2 per distance cell: centre, half width + margins
#define PENUMBRA_LUT_BINDING_TABLE 3         // uvec4 per texel: the centre masks (output)
#define PENUMBRA_LUT_BINDING_UNCERTAIN 4     // uvec4 per texel: the uncertain masks (output, certified)
#define PENUMBRA_LUT_BINDING_PARAMS 0        // uniform block PenumbraLutParamsBlock (std140)

// The parameter block: what a lookup needs to locate a plane's cell, and what the generator needs
// to fill one. std140 and std430 safe: 12 uints, 48 bytes.
struct PenumbraLutParams {
    uint resolution_normal;    // R_n: the normal grid is R_n x R_n cells
    uint resolution_distance;  // R_d: distance cells (over [0, 1] if symmetric, else [-1, 1])
    uint tables;               // sets * tables_per_set
    uint tables_per_set;       // ceil(samples_per_set / 128)
    uint samples_per_set;      // N
    uint sets;                 // K
    uint mapping;              // PENUMBRA_LUT_MAPPING_*
    uint flags;                // PENUMBRA_LUT_FLAG_*
    uint texels_per_table;     // R_n * R_n * R_d
    uint uncertain_offset;     // uvec4 index of the first uncertain texel (0 when not certified)
    uint reserved0;
    uint reserved1;
};

#ifdef __cplusplus
}  // namespace penumbra::shared
#endif

#endif
