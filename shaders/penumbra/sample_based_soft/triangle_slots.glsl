// penumbra — sample-based soft shadows, deferred pairs: the triangle slots the light pass's
// geometry stage wrote (light_pass.geom.glsl), read by the compute passes: a slot holds the
// triangle's three float vertices as bits and its draw's list block and flags, the only fields in
// which the draws' parameter blocks differ. Also the pairs' entries (unpacked) and, after
// light_pass_work.glsl in the pairs and tables passes, a slot's work on a texel
// (penumbraSbsSlotWork).
#ifndef PENUMBRA_SBS_TRIANGLE_SLOTS_GLSL
#define PENUMBRA_SBS_TRIANGLE_SLOTS_GLSL
layout(std430, binding = PENUMBRA_SBS_TRIANGLES_BINDING) readonly buffer PenumbraSbsTriangles { uint penumbraSbsTriangles[]; };

/// A deferred pair's entry (PENUMBRA_SBS_PAIR_X / _Y): its triangle slot, its view sample's index in
/// the fragment's list block, and the texel.
struct PenumbraSbsPair {
    uint triangle, index;
    uvec2 texel;
};
PenumbraSbsPair penumbraSbsUnpackPair(uvec2 pair) {
    return PenumbraSbsPair(pair.x & 0xFFFFFFu, pair.x >> 24u | (pair.y >> 26u) << 8u,
                           uvec2(pair.y & 0x1FFFu, (pair.y >> 13u) & 0x1FFFu));
}

/// Vertex `i` (0..2) of slot `slot`, in fp64 (exactly the float the fragment stage would widen).
dvec3 penumbraSbsSlotVertex(uint slot, uint i) {
    const uint base = PENUMBRA_SBS_TRIANGLE_WORDS * slot + 3u * i;
    return dvec3(uintBitsToFloat(uvec3(penumbraSbsTriangles[base], penumbraSbsTriangles[base + 1u], penumbraSbsTriangles[base + 2u])));
}

/// The parameter block of the draw that wrote slot `slot`.
PenumbraSbsParams penumbraSbsSlotParams(uint slot) {
    PenumbraSbsParams P = penumbraSbsParams;
    const uint draw = penumbraSbsTriangles[PENUMBRA_SBS_TRIANGLE_WORDS * slot + 9u];
    P.grid.w = draw & 0xFFFFu;
    P.reserved.y = draw >> 16u;
    return P;
}

#if defined(PENUMBRA_SBS_LIGHT_PASS_WORK_GLSL)  // the pairs, tables and coverage passes
/// The wedge planes the geometry stage stored in slot `slot` (SoftSkips::wedges).
PenumbraSbsWedges penumbraSbsSlotWedges(uint slot) {
    const uint base = PENUMBRA_SBS_TRIANGLE_WORDS * slot + 10u;
    PenumbraSbsWedges w;
    for (uint i = 0u; i < 4u; ++i)
        w.planes[i] = uintBitsToFloat(uvec4(penumbraSbsTriangles[base + 4u * i], penumbraSbsTriangles[base + 4u * i + 1u],
                                            penumbraSbsTriangles[base + 4u * i + 2u], penumbraSbsTriangles[base + 4u * i + 3u]));
    w.margin = uintBitsToFloat(uvec2(penumbraSbsTriangles[base + 16u], penumbraSbsTriangles[base + 17u]));
    return w;
}
#endif

#if defined(PENUMBRA_SBS_LIGHT_PASS_WORK_GLSL) && PENUMBRA_SBS_STAGE != 0  // the pairs and tables passes

/// The compute passes' work (light_pass_work.glsl's penumbraSbsTexelWork) of slot `slot`'s triangle
/// on `texel`'s list block of the slot's draw: the whole block, or only its sample `index`
/// (PENUMBRA_SBS_WHOLE_BLOCK: all; the wedge planes tested there, a single sample's pair passed
/// them in the fragment stage). Returns the range of list slots walked (penumbraSbsWedged of them
/// skipped by the wedges).
#define PENUMBRA_SBS_WHOLE_BLOCK 0xFFFFFFFFu
uvec2 penumbraSbsSlotWork(uint slot, uvec2 texel, uint index) {
    const PenumbraSbsParams P = penumbraSbsSlotParams(slot);
    penumbraSbsTestTriangle = slot;
    uvec2 range = penumbraSampleListsBlock(ivec2(texel), P.grid.w, P.grid.z);
    if (index != PENUMBRA_SBS_WHOLE_BLOCK) range = uvec2(range.x + index, 1u);
#if PENUMBRA_SBS_WEDGES
    const PenumbraSbsWedges wedges = index == PENUMBRA_SBS_WHOLE_BLOCK ? penumbraSbsSlotWedges(slot) : penumbraSbsNoWedges();
#else
    const PenumbraSbsWedges wedges = penumbraSbsNoWedges();
#endif
    penumbraSbsTexelWork(P, texel, range, penumbraSbsSlotVertex(slot, 0u), penumbraSbsSlotVertex(slot, 1u),
                         penumbraSbsSlotVertex(slot, 2u), wedges);
    return range;
}
#endif
#endif
