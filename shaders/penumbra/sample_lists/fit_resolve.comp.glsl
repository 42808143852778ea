// penumbra — §4.3 light-frustum fitting, second half: turns the keys fit.comp.glsl reduced into
// the header (box of the projected samples, deepest sample, farthest distance) into the cropped
// light view-projection and its light-texture matrix, written to the frustum buffer that the
// count pass and the integrator's light pass read as a uniform block. One invocation; the
// fitted frustum never travels through the CPU (no read-back, no stall).
//
// Twin: penumbra::lightFrustumFitFromHeader (include/penumbra/sample_lists.hpp) performs the same
// double-precision operations in the same order (`precise`: no fusing), then rounds to float
// like the host. Bit-equality with it needs correctly rounded fp64 add/mul/div and double->float
// conversion (llvmpipe); GLSL 4.50 only promises fp64 at least as precise as fp32, so elsewhere
// the matrices may differ in low bits — harmless for correctness: every later pass, and the light
// pass, use the GPU's own matrix (see sample_lists.hpp, "Rules").
//
// Bindings (defaults): uniform block 0 params; SSBO 3 header (read), 2 frustum (written).
#include "penumbra/sample_lists/sample_lists_shared.h"

layout(local_size_x = 1) in;

layout(std140, binding = PENUMBRA_SAMPLE_LISTS_BINDING_PARAMS) uniform PenumbraSampleListsParamsBlock {
    PenumbraSampleListsParams penumbraSampleListsParams;
};
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_HEADER) readonly buffer PenumbraSampleListsHeaderBlock {
    PenumbraSampleListsHeader penumbraSampleListsHeader;
};
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM_OUT) writeonly buffer PenumbraSampleListsFrustumOutBlock {
    PenumbraSampleListsFrustum penumbraSampleListsFrustumOut;
};

// Twin of penumbra::detail::orderKeyValue.
float penumbraSampleListsOrderKeyValue(uint key) {
    return uintBitsToFloat((key & 0x80000000u) != 0u ? (key & 0x7FFFFFFFu) : ~key);
}

// Twin of penumbra::detail::biasLightTexture: bias * m with the bias written out (x, y and, unless
// the light's depth is [0, 1] already, z mapped from [-w, w] to [0, w]).
mat4 penumbraSampleListsBias(mat4 m, bool depthZeroToOne) {
    mat4 t;
    for (int j = 0; j < 4; ++j) {
        precise float x = m[j][0] * 0.5 + m[j][3] * 0.5;
        precise float y = m[j][1] * 0.5 + m[j][3] * 0.5;
        precise float z = m[j][2] * 0.5 + m[j][3] * 0.5;
        t[j] = vec4(x, y, depthZeroToOne ? m[j][2] : z, m[j][3]);
    }
    return t;
}

void main() {
    const PenumbraSampleListsParams params = penumbraSampleListsParams;
    const PenumbraSampleListsHeader h = penumbraSampleListsHeader;
    PenumbraSampleListsFrustum f;
    f.crop = mat4(1.0);
    f.box = vec4(0.0);
    f.extent = vec4(0.0);
    f.info = uvec4(0u, h.fit_samples, 0u, 0u);
    if (h.fit_samples == 0u) {
        f.view_projection = params.light_view_projection;
        f.light_texture = params.light_texture;
        penumbraSampleListsFrustumOut = f;
        return;
    }
    f.info.x = 1u;
    const float u0 = penumbraSampleListsOrderKeyValue(h.fit_min_u), v0 = penumbraSampleListsOrderKeyValue(h.fit_min_v);
    const float u1 = penumbraSampleListsOrderKeyValue(h.fit_max_u), v1 = penumbraSampleListsOrderKeyValue(h.fit_max_v);
    const float max_depth = penumbraSampleListsOrderKeyValue(h.fit_max_depth);
    const float distance_key = penumbraSampleListsOrderKeyValue(h.fit_max_distance);
    f.box = vec4(u0, v0, u1, v1);
    precise double far_distance;
    if (params.light.w == 0.0) {
        precise dvec3 l = dvec3(params.light.xyz);
        precise double squared = l.x * l.x + l.y * l.y;
        squared = squared + l.z * l.z;
        far_distance = double(distance_key) / sqrt(squared);
    } else {
        far_distance = sqrt(double(distance_key));
    }
    f.extent = vec4(max_depth, float(far_distance), 0.0, 0.0);
    const double margin = double(params.fit.x), min_margin = double(params.fit.y);
    precise double mu = max(margin * (double(u1) - double(u0)), min_margin);
    precise double mv = max(margin * (double(v1) - double(v0)), min_margin);
    precise double U0 = double(u0) - mu, U1 = double(u1) + mu;
    precise double V0 = double(v0) - mv, V1 = double(v1) + mv;
    precise double c00 = 1.0LF / (U1 - U0);
    precise double c30 = ((1.0LF - U0) - U1) / (U1 - U0);
    precise double c11 = 1.0LF / (V1 - V0);
    precise double c31 = ((1.0LF - V0) - V1) / (V1 - V0);
    precise double c22 = 1.0LF, c32 = 0.0LF;
    const uint flags = params.grid.w;
    if ((flags & PENUMBRA_SAMPLE_LISTS_FLAG_FIT_FAR) != 0u && (flags & PENUMBRA_SAMPLE_LISTS_FLAG_CLIP_DEPTH) != 0u) {
        const double zmax = double(max_depth);
        precise double Z = zmax + max(margin * zmax, min_margin);
        if (Z < 1.0LF && Z > 0.0LF) {
            c22 = 1.0LF / Z;
            if ((flags & PENUMBRA_SAMPLE_LISTS_FLAG_LIGHT_DEPTH_ZERO_TO_ONE) == 0u) c32 = c22 - 1.0LF;
        }
    }
    f.crop = mat4(1.0);
    f.crop[0][0] = float(c00);
    f.crop[3][0] = float(c30);
    f.crop[1][1] = float(c11);
    f.crop[3][1] = float(c31);
    f.crop[2][2] = float(c22);
    f.crop[3][2] = float(c32);
    // crop * view_projection in double, written out (the crop is sparse), then rounded to float.
    const mat4 m = params.light_view_projection;
    for (int j = 0; j < 4; ++j) {
        precise double x = c00 * double(m[j][0]) + c30 * double(m[j][3]);
        precise double y = c11 * double(m[j][1]) + c31 * double(m[j][3]);
        precise double z = c22 * double(m[j][2]) + c32 * double(m[j][3]);
        f.view_projection[j] = vec4(float(x), float(y), float(z), m[j][3]);
    }
    f.light_texture = penumbraSampleListsBias(f.view_projection,
                                              (flags & PENUMBRA_SAMPLE_LISTS_FLAG_LIGHT_DEPTH_ZERO_TO_ONE) != 0u);
    penumbraSampleListsFrustumOut = f;
}
