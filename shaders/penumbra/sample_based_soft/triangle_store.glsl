// penumbra — sample-based soft shadows: what the raster light pass's geometry stage
// (light_pass.geom.glsl) and the compute light pass's caster setup (light_pass_setup.comp.glsl)
// both do with a caster triangle: SoftSkips::closed_casters' cull, and the writes of its triangle
// slot (triangle_slots.glsl reads them) and of its region record (the coverage pass reads them).
// Needs penumbraSbsParams and caster_plane.glsl; the writes (PENUMBRA_SBS_TRIANGLES_WRITABLE defined:
// the triangles buffer is declared writable as penumbraSbsTriangles) wedges.glsl
// (PENUMBRA_SBS_WEDGES), and the record's also PENUMBRA_SBS_REGION_BASE and the influence region's
// penumbraInfluenceOut.
#ifndef PENUMBRA_SBS_TRIANGLE_STORE_GLSL
#define PENUMBRA_SBS_TRIANGLE_STORE_GLSL

// SoftSkips::closed_casters for a triangle of this draw or dispatch: true when the pass does not
// take it. Of a closed caster, a triangle with the whole light strictly behind its plane is never
// the face a blocked segment leaves the solid through: the first pass culls it (`away`); the
// second (PENUMBRA_SBS_FLAG_CULLED_PASS) takes exactly those, for the samples within the oracle's
// coplanar reach of a kept closed triangle.
bool penumbraSbsClosedSkips(vec3 v0, vec3 v1, vec3 v2, out bool away) {
    away = false;
    if ((penumbraSbsParams.reserved.y & PENUMBRA_SBS_FLAG_CULL_CLOSED) == 0u) return false;
    const PenumbraSbsCasterPlane c =
        penumbraSbsCasterPlane(dvec3(v0), dvec3(v1), dvec3(v2), penumbraSbsParams.center.xyz, penumbraSbsParams.bounds.x);
    away = penumbraSbsCasterFacesAway(c);
    return away != ((penumbraSbsParams.reserved.y & PENUMBRA_SBS_FLAG_CULLED_PASS) != 0u);
}

#ifdef PENUMBRA_SBS_TRIANGLES_WRITABLE
// Slot k: the vertices' bits, then the list block and the flags (what the compute passes need of
// the parameter block), then the wedge planes (SoftSkips::wedges).
void penumbraSbsStoreSlot(uint k, vec3 v0, vec3 v1, vec3 v2, uint list_block
#if PENUMBRA_SBS_WEDGES
                          , PenumbraSbsWedges wedges
#endif
) {
    const uint base = PENUMBRA_SBS_TRIANGLE_WORDS * k;
    const vec3 v[3] = vec3[3](v0, v1, v2);
    for (uint i = 0u; i < 9u; ++i) penumbraSbsTriangles[base + i] = floatBitsToUint(v[i / 3u][i % 3u]);
    penumbraSbsTriangles[base + 9u] = list_block | penumbraSbsParams.reserved.y << 16u;
#if PENUMBRA_SBS_WEDGES
    for (uint i = 0u; i < 16u; ++i) penumbraSbsTriangles[base + 10u + i] = floatBitsToUint(wedges.planes[i / 4u][i % 4u]);
    penumbraSbsTriangles[base + 26u] = floatBitsToUint(wedges.margin.x);
    penumbraSbsTriangles[base + 27u] = floatBitsToUint(wedges.margin.y);
#endif
}

#ifdef PENUMBRA_SBS_REGION_BASE
// Record r: slot, then the polygon penumbraInfluenceOut[0, count) as float bits.
void penumbraSbsStoreRecord(uint r, uint slot, int count) {
    const uint base = uint(PENUMBRA_SBS_REGION_BASE) + PENUMBRA_SBS_REGION_WORDS(PENUMBRA_INFLUENCE_SIDES) * r;
    penumbraSbsTriangles[base] = slot;
    penumbraSbsTriangles[base + 1u] = uint(count);
    for (int j = 0; j < count; ++j) {
        penumbraSbsTriangles[base + 2u + 2u * uint(j)] = floatBitsToUint(penumbraInfluenceOut[j].x);
        penumbraSbsTriangles[base + 3u + 2u * uint(j)] = floatBitsToUint(penumbraInfluenceOut[j].y);
    }
}
#endif
#endif

#endif
