// penumbra — §4.3 light-frustum fitting ("fit the frustum to a minimal 2D-axis aligned bounding box
// of the projected view-samples ... The same step also computes the maximum view-sample distance
// to the light source. This allows us to fit an optimal far plane."). A parallel reduction over
// the samples the count pass would accept: each work group reduces in shared memory with atomics
// on order-preserving float keys (penumbraSampleListsOrderKey), then one atomic per quantity and
// group goes to the header; fit_resolve.comp.glsl turns the keys into the crop matrix on
// the GPU, exactly as the CPU twin penumbra::lightFrustumFitFromHeader does.
//
// penumbra-permutation: PENUMBRA_SAMPLE_LISTS_INPUT=0
// penumbra-permutation: PENUMBRA_SAMPLE_LISTS_INPUT=1
//
// Bindings: uniform block 0 = params; buffer input: SSBO 0 positions, 1 normals; depth input:
// texture units 0 depth, 1 normals; SSBO 3 header (fit keys initialised by the host).
#include "penumbra/sample_lists/kernel.glsl"

layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_HEADER) buffer PenumbraSampleListsHeaderBlock {
    PenumbraSampleListsHeader penumbraSampleListsHeader;
};

// min u, min v, max u, max v, max depth, max distance (keys), sample count.
shared uint penumbraSampleListsFitShared[7];

void main() {
    const uint local = gl_LocalInvocationID.x;
    if (local < 7u) penumbraSampleListsFitShared[local] = local < 2u ? 0xFFFFFFFFu : 0u;
    barrier();

    uint id;
    if (penumbraSampleListsSampleId(id)) {
        const vec4 light = penumbraSampleListsParams.light;
        vec4 position = penumbraSampleListsLoadPosition(penumbraSampleListsParams, id);
        vec3 normal = penumbraSampleListsLoadNormal(penumbraSampleListsParams, id);
        vec4 t;
        uint code = penumbraSampleListsClassify(penumbraSampleListsParams.light_texture, light,
                                                penumbraSampleListsParams.grid, position, normal, t);
        if (code < PENUMBRA_SAMPLE_LISTS_REJECTED) {
            precise float u = t.x / t.w;
            precise float v = t.y / t.w;
            precise float depth = t.z / t.w;
            precise float distance;
            if (light.w == 0.0) {
                // Directional: how far along the light's travel direction (unnormalised).
                precise float along = position.x * light.x + position.y * light.y;
                along = along + position.z * light.z;
                distance = -along;
            } else {
                // Point: squared distance (sqrt on the host keeps GPU and CPU keys identical).
                precise vec3 d = position.xyz - light.xyz;
                precise float squared = d.x * d.x + d.y * d.y;
                distance = squared + d.z * d.z;
            }
            atomicMin(penumbraSampleListsFitShared[0], penumbraSampleListsOrderKey(u));
            atomicMin(penumbraSampleListsFitShared[1], penumbraSampleListsOrderKey(v));
            atomicMax(penumbraSampleListsFitShared[2], penumbraSampleListsOrderKey(u));
            atomicMax(penumbraSampleListsFitShared[3], penumbraSampleListsOrderKey(v));
            atomicMax(penumbraSampleListsFitShared[4], penumbraSampleListsOrderKey(depth));
            atomicMax(penumbraSampleListsFitShared[5], penumbraSampleListsOrderKey(distance));
            atomicAdd(penumbraSampleListsFitShared[6], 1u);
        }
    }
    barrier();

    if (local < 7u && penumbraSampleListsFitShared[6] != 0u) {
        uint key = penumbraSampleListsFitShared[local];
        if (local == 0u) atomicMin(penumbraSampleListsHeader.fit_min_u, key);
        else if (local == 1u) atomicMin(penumbraSampleListsHeader.fit_min_v, key);
        else if (local == 2u) atomicMax(penumbraSampleListsHeader.fit_max_u, key);
        else if (local == 3u) atomicMax(penumbraSampleListsHeader.fit_max_v, key);
        else if (local == 4u) atomicMax(penumbraSampleListsHeader.fit_max_depth, key);
        else if (local == 5u) atomicMax(penumbraSampleListsHeader.fit_max_distance, key);
        else atomicAdd(penumbraSampleListsHeader.fit_samples, key);
    }
}
