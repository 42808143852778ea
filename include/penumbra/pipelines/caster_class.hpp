// penumbra/pipelines/caster_class.hpp — what the pipelines know of the casters: their class, and
// (for the compute light passes) where their triangles lie.
//   Closed: watertight, edge-manifold meshes, consistently oriented with outward normals (unions of
//           such meshes qualify); the pipelines may cull some of their triangles (§3.3 / §4.3).
//   Open:   everything else (ground planes, foliage cards, meshes with holes).
// scene::Mesh::closed (support code) is a checked way to classify an indexed mesh.
#ifndef PENUMBRA_PIPELINES_CASTER_CLASS_HPP
#define PENUMBRA_PIPELINES_CASTER_CLASS_HPP

#include "penumbra/buffer_range.hpp"

#include <cstdint>

namespace penumbra {

enum class CasterClass { Closed, Open };

/// Casters as buffers (the compute light passes: SoftLightPass::Compute, AfhLightPass::Compute): `triangles` triangles of
/// one class. Vertex v's position is the 3 floats at byte offset v * stride of `positions` (in the
/// frame of the view samples and the light); triangle t's vertices are indices[3t .. 3t + 2]
/// (uint32) or, with `indices` empty, 3t .. 3t + 2. The shaders read them through
/// penumbra/sample_based_soft/caster_buffer.glsl, a hook you may replace in your ShaderLibrary
/// (packed positions, skinning, instancing). A triangle with an index past `positions` casts
/// nothing and is counted (SampleBasedSoftFrame / AliasFreeHardFrame::caster_indices_out_of_range).
struct CasterBuffer {
    BufferRange positions;  ///< offset a multiple of GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT
    uint32_t stride = 12;   ///< bytes between vertices: a multiple of 4, at least 12
    BufferRange indices;    ///< uint32 per corner; empty = non-indexed; same alignment rule
    uint32_t triangles = 0;
    CasterClass caster_class = CasterClass::Open;
};

/// Triangles per CasterBuffer at most (3 corners each stay below 2^32).
inline constexpr uint32_t kMaxCasterTriangles = 1u << 30;

/// Bytes `c`'s positions must hold: one vertex with indices (the shaders check each index against
/// the range), 3 per triangle without.
inline uint64_t casterPositionBytes(const CasterBuffer& c) {
    return c.indices.empty() ? (3 * uint64_t(c.triangles) - 1) * c.stride + 12 : 12;
}

/// The per-frame check of `count` caster ranges (no GL call, no throw; ranges of 0 triangles are
/// skipped): InvalidArgument for a null array, a stride below 12 or not a multiple of 4, more than
/// kMaxCasterTriangles or an unknown class; RangeTooSmall for ranges that cannot hold their
/// triangles; Misaligned for offsets that are not multiples of `ssbo_alignment`
/// (GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT).
inline Status checkCasterBuffers(const CasterBuffer* casters, uint32_t count, uint32_t ssbo_alignment) {
    if (count > 0 && casters == nullptr) return Status::InvalidArgument;
    for (uint32_t i = 0; i < count; ++i) {
        const CasterBuffer& c = casters[i];
        if (c.triangles == 0) continue;
        if (c.stride < 12 || c.stride % 4 != 0 || c.triangles > kMaxCasterTriangles ||
            (c.caster_class != CasterClass::Closed && c.caster_class != CasterClass::Open))
            return Status::InvalidArgument;
        if (!c.positions.holds(casterPositionBytes(c)) || (!c.indices.empty() && !c.indices.holds(uint64_t(c.triangles) * 12)))
            return Status::RangeTooSmall;
        if (c.positions.offset % ssbo_alignment != 0 || (!c.indices.empty() && c.indices.offset % ssbo_alignment != 0))
            return Status::Misaligned;
    }
    return Status::Ok;
}

}  // namespace penumbra

#endif
