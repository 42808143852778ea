// penumbra — light-sample LUT lookups (sintorn2008 §4.2, Fig. 6: the bit mask of the light samples
// behind a plane, AND-ed over a caster's planes) and the exact test they are checked against. CPU
// twins in include/penumbra/light_lut.hpp, operation for operation (`precise` here, opaque products
// there): penumbraLutLocate = lightLutLocate<float>, penumbraLutLookup = lightLutLookup<float>
// (= penumbraLutLookupCell / penumbraLutCentreCell at penumbraLutLocate's cell, the split a caller
// uses to locate a plane once for several tables), penumbraExactBehind = exactBehind<float>,
// penumbraLutCombine = lutCombine, penumbraLutResolve = lutResolve, penumbraLutValidMask =
// lightLutValidMask. The exact test and resolve equal exactBehindOracle (fp64 on the float inputs)
// wherever fp64 + and * are IEEE (a float filter decides, fp64 only near the plane); on any
// conforming driver, every bit the filter decides is the oracle's. With correctly rounded float +, *, / and
// sqrt (llvmpipe, most desktop GPUs) the octahedral lookups equal the twins bit for bit; the
// two-angle mapping uses acos/atan, whose GLSL precision is unspecified, so there the cell may
// differ near cell borders (the certificate covers that only when the driver is within
// LightLutOptions::tolerance; see light_lut.hpp).
//
// Planes are in the light's normalised space: (n, w) with a sample q behind when dot(n, q) + w < 0,
// strictly; n need not be unit. A plane with a non-finite value or a zero normal has the documented
// empty mask (nothing behind, certain); one that misses the bounding sphere is answered without the
// table (d >= 1: nothing, d <= -1: every sample, certain).
//
// Hooks the integrator defines before including this file:
//   PENUMBRA_LUT_PARAMS            -> PenumbraLutParams of the LUT (e.g. a uniform block member)
//   PENUMBRA_LUT_LOAD(index)       -> uvec4 number `index` of the LUT (SSBO element, or a texelFetch
//                                     of the RGBA32UI 3D texture of that table; index = table *
//                                     texels_per_table + texel, + uncertain_offset for the
//                                     uncertain masks)
//   PENUMBRA_LUT_SAMPLE(table, bit) -> vec3, sample `bit` of table `table` in the light's
//                                     normalised space, as float (for the exact test and resolve;
//                                     every |coordinate| <= 1, which its error bound relies on)
#ifndef PENUMBRA_LIGHT_LUT_LOOKUP_GLSL
#define PENUMBRA_LIGHT_LUT_LOOKUP_GLSL

#include "penumbra/light_lut/light_lut_shared.h"

#ifndef PENUMBRA_LUT_PARAMS
#error "penumbra/light_lut/lookup.glsl: define the hook PENUMBRA_LUT_PARAMS (-> PenumbraLutParams)"
#endif
#ifndef PENUMBRA_LUT_LOAD
#error "penumbra/light_lut/lookup.glsl: define the hook PENUMBRA_LUT_LOAD(index) (-> uvec4 of the LUT)"
#endif
#ifndef PENUMBRA_LUT_SAMPLE
#error "penumbra/light_lut/lookup.glsl: define the hook PENUMBRA_LUT_SAMPLE(table, bit) (-> vec3 light sample)"
#endif

// Where a plane's answer comes from (penumbra::LutCell): trivial 0 reads texel `texel` (flip:
// complement the centre mask, symmetric table read for (-n, -d)); +1 every sample behind; -1 none.
struct PenumbraLutCell {
    uint texel;
    bool flip;
    int trivial;
};

// NaN or Inf, on the bits (no isnan/isinf, which drivers may fold away).
bool penumbraLutNonFinite(float f) {
    return (floatBitsToUint(f) & 0x7F800000u) == 0x7F800000u;
}

PenumbraLutCell penumbraLutLocate(PenumbraLutParams p, vec4 plane) {
    PenumbraLutCell cell = PenumbraLutCell(0u, false, -1);
    vec3 n = plane.xyz;
    precise float length2 = (n.x * n.x + n.y * n.y) + n.z * n.z;
    precise float len = sqrt(length2);
    if (!(len > 0.0) || penumbraLutNonFinite(len) || penumbraLutNonFinite(plane.w)) return cell;
    precise float d = plane.w / len;
    if (d >= 1.0) return cell;
    if (d <= -1.0) {
        cell.trivial = 1;
        return cell;
    }
    cell.trivial = 0;
    const bool symmetric = (p.flags & uint(PENUMBRA_LUT_FLAG_SYMMETRIC)) != 0u;
    if (symmetric && d < 0.0) {
        cell.flip = true;
        n = -n;
        d = -d;
    }
    const int rn = int(p.resolution_normal), rd = int(p.resolution_distance);
    const float half_rn = 0.5 * float(rn);
    int i, j;
    if (p.mapping == uint(PENUMBRA_LUT_MAPPING_OCTAHEDRAL)) {
        precise float sum = (abs(n.x) + abs(n.y)) + abs(n.z);
        precise float u = n.x / sum;
        precise float v = n.y / sum;
        if (n.z < 0.0) {
            precise float fu = 1.0 - abs(v);
            precise float fv = 1.0 - abs(u);
            u = u < 0.0 ? -fu : fu;
            v = v < 0.0 ? -fv : fv;
        }
        precise float gu = (u + 1.0) * half_rn;
        precise float gv = (v + 1.0) * half_rn;
        i = int(floor(gu));
        j = int(floor(gv));
    } else {
        const float kPi = 3.14159265358979323846;
        precise float z = clamp(n.z / len, -1.0, 1.0);
        precise float theta = acos(z);
        precise float phi = atan(n.y, n.x);
        precise float gt = (theta / kPi) * float(rn);
        precise float gp = ((phi + kPi) / (2.0 * kPi)) * float(rn);
        j = int(floor(gt));
        i = int(floor(gp));
    }
    i = clamp(i, 0, rn - 1);
    j = clamp(j, 0, rn - 1);
    precise float dk = symmetric ? d * float(rd) : (d + 1.0) * (0.5 * float(rd));
    const int k = clamp(int(floor(dk)), 0, rd - 1);
    cell.texel = uint((k * rn + j) * rn + i);
    return cell;
}

// Samples in table `table` (of a set of samples_per_set): how many (<= 128).
uint penumbraLutSampleCount(PenumbraLutParams p, uint table) {
    const uint block = table % p.tables_per_set;
    return min(uint(PENUMBRA_LUT_SAMPLES_PER_TABLE), p.samples_per_set - block * 128u);
}

// The bits of table `table` that stand for real samples (lightLutValidMask).
uvec4 penumbraLutValidMask(PenumbraLutParams p, uint table) {
    // Per word min(32, max(0, count - 32 w)) low bits, with constant indices (no per-lane array).
    const ivec4 bits = clamp(ivec4(penumbraLutSampleCount(p, table)) - ivec4(0, 32, 64, 96), ivec4(0), ivec4(32));
    const uvec4 low = (uvec4(1u) << uvec4(min(bits, ivec4(31)))) - 1u;  // shifts stay below 32
    return mix(low, uvec4(0xFFFFFFFFu), equal(bits, ivec4(32)));
}

// The centre mask of table `table` at a located cell (complemented when flipped): seed mode's
// answer. The cell does not depend on the table: a caller looking one plane up in several tables
// (a set of more than 128 samples) locates it once.
uvec4 penumbraLutCentreCell(PenumbraLutCell cell, uint table) {
    const PenumbraLutParams p = PENUMBRA_LUT_PARAMS;
    const uvec4 valid = penumbraLutValidMask(p, table);
    if (cell.trivial != 0) return cell.trivial > 0 ? valid : uvec4(0u);
    const uvec4 centre = PENUMBRA_LUT_LOAD(table * p.texels_per_table + cell.texel);
    return cell.flip ? ~centre & valid : centre;
}

// lightLutLookup for a located cell: the centre mask and, for a certified LUT, the uncertain mask
// (0 for a seed-mode LUT and for trivial planes).
uvec4 penumbraLutLookupCell(PenumbraLutCell cell, uint table, out uvec4 uncertain) {
    const PenumbraLutParams p = PENUMBRA_LUT_PARAMS;
    uncertain = uvec4(0u);
    if (cell.trivial == 0 && (p.flags & uint(PENUMBRA_LUT_FLAG_CERTIFIED)) != 0u)
        uncertain = PENUMBRA_LUT_LOAD(p.uncertain_offset + table * p.texels_per_table + cell.texel);
    return penumbraLutCentreCell(cell, table);
}

// lightLutLookup: penumbraLutLookupCell at the plane's cell.
uvec4 penumbraLutLookup(vec4 plane, uint table, out uvec4 uncertain) {
    return penumbraLutLookupCell(penumbraLutLocate(PENUMBRA_LUT_PARAMS, plane), table, uncertain);
}

// Seed mode (centre sampling): the samples behind the cell's centre plane.
uvec4 penumbraLutBehind(vec4 plane, uint table) {
    return penumbraLutCentreCell(penumbraLutLocate(PENUMBRA_LUT_PARAMS, plane), table);
}

// Certified mode: the samples certainly behind (lutCertain: centre & ~uncertain) and the uncertain
// ones; every other valid sample is certainly in front. With a seed-mode LUT uncertain is 0.
uvec4 penumbraLutBehindCertified(vec4 plane, uint table, out uvec4 uncertain) {
    const uvec4 centre = penumbraLutLookup(plane, table, uncertain);
    return centre & ~uncertain;
}

// The error bound of the float side test for `plane` (detail::light_lut::exactBound): the float
// value of dot(n, q) + w with |s| above it has the fp64 value's sign (proof in light_lut.hpp,
// "Exact side test"). Computed once per plane; NaN or Inf planes give no bound that passes.
float penumbraLutExactBound(vec4 plane) {
    precise float s = ((abs(plane.x) + abs(plane.y)) + abs(plane.z)) + abs(plane.w);
    precise float b = float(PENUMBRA_LUT_EXACT_REL) * s + float(PENUMBRA_LUT_EXACT_ABS);
    return b;
}

// The exact side of one sample, dot(n, q) + w < 0 (exactBehind<float>, = exactBehindOracle): the
// float value where it clears `bound`, else the fp64 value (products of floats are exact in fp64).
// A float value alone is not exact: it rounds to 0 or flips sign within ~1e-7 of the plane.
bool penumbraLutSampleBehindBounded(vec4 plane, float bound, uint table, uint bit) {
    const vec3 q = PENUMBRA_LUT_SAMPLE(table, bit);
    precise float s = ((plane.x * q.x + plane.y * q.y) + plane.z * q.z) + plane.w;
    if (abs(s) > bound) return s < 0.0;
    precise double sd = ((double(plane.x) * double(q.x) + double(plane.y) * double(q.y)) + double(plane.z) * double(q.z)) +
                        double(plane.w);
    return sd < 0.0LF;
}

bool penumbraLutSampleBehind(vec4 plane, uint table, uint bit) {
    return penumbraLutSampleBehindBounded(plane, penumbraLutExactBound(plane), table, bit);
}

// The ground truth: every sample of the table tested against the plane (slow: 128 tests).
uvec4 penumbraExactBehind(vec4 plane, uint table) {
    const uint count = penumbraLutSampleCount(PENUMBRA_LUT_PARAMS, table);
    const float bound = penumbraLutExactBound(plane);
    uvec4 m = uvec4(0u);
    for (uint b = 0u; b < count; ++b) {
        if (penumbraLutSampleBehindBounded(plane, bound, table, b)) m[b >> 5u] |= 1u << (b & 31u);
    }
    return m;
}

// sintorn2008 Fig. 6: the samples a caster blocks are behind every one of its planes (AND). With
// certified inputs (lutCombine): certain behind only if certain behind in both; certain in front
// if certain in front in either; else uncertain.
void penumbraLutCombine(inout uvec4 certain, inout uvec4 uncertain, uvec4 certain2, uvec4 uncertain2) {
    const uvec4 front_a = ~(certain | uncertain), front_b = ~(certain2 | uncertain2);
    certain = certain & certain2;
    uncertain = ~(certain | front_a | front_b);
}

// The exact mask from a certified answer (lutResolve): the certain bits as they are, each
// uncertain sample (of the valid ones) tested against `plane`, one exact test per set bit.
uvec4 penumbraLutResolve(vec4 plane, uint table, uvec4 certain, uvec4 uncertain) {
    uvec4 m = certain;
    uncertain &= penumbraLutValidMask(PENUMBRA_LUT_PARAMS, table);
    const float bound = penumbraLutExactBound(plane);
    for (uint w = 0u; w < 4u; ++w) {
        uint bits = uncertain[w];
        while (bits != 0u) {
            const uint b = uint(findLSB(bits));
            bits &= bits - 1u;
            if (penumbraLutSampleBehindBounded(plane, bound, table, 32u * w + b)) m[w] |= 1u << b;
        }
    }
    return m;
}

// The plane with its normal rotated about the light's local z axis by -angle (cos_angle,
// sin_angle = cos, sin of the angle): looking it up equals looking the plane up against the
// samples rotated by +angle, the per-pixel rotation of a rotationally symmetric light's samples
// (issue 8; laine2005 §3.4: banding becomes noise). n' = (c x + s y, c y - s x, z), w kept.
vec4 penumbraLutRotate(vec4 plane, float cos_angle, float sin_angle) {
    precise float x = plane.x * cos_angle + plane.y * sin_angle;
    precise float y = plane.y * cos_angle - plane.x * sin_angle;
    return vec4(x, y, plane.z, plane.w);
}

#endif
