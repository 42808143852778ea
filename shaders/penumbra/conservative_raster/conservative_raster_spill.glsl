// penumbra — the spill buffer of the Fixed-6 two-pass plan (sintorn2008 §3.2 keeps the geometry
// stage at 6 output vertices; triangles that need clipping take a second pass).
//
// Integration summary
//   needs:    a std430 buffer holding a PenumbraConservativeSpillHeader followed by an array of
//             PenumbraConservativeSpillTriangle (conservative_raster_shared.h), sized and reset
//             from penumbra::ConservativeRasterSetup::spill (the plan), and two hooks naming its
//             members (lvalues in your buffer block):
//               PENUMBRA_CONSERVATIVE_SPILL_HEADER     the PenumbraConservativeSpillHeader
//               PENUMBRA_CONSERVATIVE_SPILL_TRIANGLES  the PenumbraConservativeSpillTriangle[] array
//   call:     bool penumbraConservativeSpillAppend(vec4 clip0, vec4 clip1, vec4 clip2, uvec4 payload)
//             from your PENUMBRA_CONSERVATIVE_SPILL hook in the direct pass. Returns false when the
//             array is full: the triangle is lost and header.overflow counts it (size the capacity
//             so that never happens: the setup's default holds every triangle of the draw).
//             Keeps header.count == 3 * min(appended, capacity), so the header's first four words
//             are the spill pass's DrawArraysIndirectCommand as they stand.
//   spill pass: glDrawArraysIndirect(GL_TRIANGLES, header offset) after
//             glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT); its geometry
//             stage (max_vertices = PENUMBRA_CONSERVATIVE_MAX_VERTICES, PENUMBRA_CONSERVATIVE_DIRECT 0)
//             reads triangle gl_PrimitiveIDIn and calls penumbraConservativeEmit on its clip
//             coordinates: the same bits the direct pass received, hence the same hull as the
//             single pass. No vertex attributes are needed (bind an empty vertex array).
#ifndef PENUMBRA_CONSERVATIVE_RASTER_SPILL_GLSL
#define PENUMBRA_CONSERVATIVE_RASTER_SPILL_GLSL

#include "penumbra/conservative_raster/conservative_raster_shared.h"

#ifndef PENUMBRA_CONSERVATIVE_SPILL_HEADER
#error penumbra/conservative_raster/conservative_raster_spill.glsl needs the hook PENUMBRA_CONSERVATIVE_SPILL_HEADER (your buffer's PenumbraConservativeSpillHeader)
#endif
#ifndef PENUMBRA_CONSERVATIVE_SPILL_TRIANGLES
#error penumbra/conservative_raster/conservative_raster_spill.glsl needs the hook PENUMBRA_CONSERVATIVE_SPILL_TRIANGLES (your buffer's PenumbraConservativeSpillTriangle[] array)
#endif

bool penumbraConservativeSpillAppend(vec4 clip0, vec4 clip1, vec4 clip2, uvec4 payload) {
    uint slot = atomicAdd(PENUMBRA_CONSERVATIVE_SPILL_HEADER.count, 3u) / 3u;
    if (slot >= PENUMBRA_CONSERVATIVE_SPILL_HEADER.capacity) {
        // Take the 3 back: only appends that found the array full ever do, and each found count
        // >= 3 * capacity, so the count settles at exactly 3 * capacity.
        atomicAdd(PENUMBRA_CONSERVATIVE_SPILL_HEADER.count, 0xfffffffdu);
        atomicAdd(PENUMBRA_CONSERVATIVE_SPILL_HEADER.overflow, 1u);
        return false;
    }
    PENUMBRA_CONSERVATIVE_SPILL_TRIANGLES[slot].clip0 = clip0;
    PENUMBRA_CONSERVATIVE_SPILL_TRIANGLES[slot].clip1 = clip1;
    PENUMBRA_CONSERVATIVE_SPILL_TRIANGLES[slot].clip2 = clip2;
    PENUMBRA_CONSERVATIVE_SPILL_TRIANGLES[slot].payload = payload;
    return true;
}

#endif
