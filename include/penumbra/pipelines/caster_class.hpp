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

/// Casters as buffers (the compute light pass, SoftLightPass::Compute): `triangles` triangles of
/// one class. Vertex v's position is the 3 floats at byte offset v * stride of `positions` (in the
/// frame of the view samples and the light); triangle t's vertices are indices[3t .. 3t + 2]
/// (uint32) or, with `indices` empty, 3t .. 3t + 2. The shaders read them through
/// penumbra/sample_based_soft/caster_buffer.glsl, a hook you may replace in your ShaderLibrary
/// (packed positions, skinning, instancing). A triangle with an index past `positions` casts
/// nothing and is counted (SampleBasedSoftFrame::caster_indices_out_of_range).
struct CasterBuffer {
    BufferRange positions;  ///< offset a multiple of GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT
    uint32_t stride = 12;   ///< bytes between vertices: a multiple of 4, at least 12
    BufferRange indices;    ///< uint32 per corner; empty = non-indexed; same alignment rule
    uint32_t triangles = 0;
    CasterClass caster_class = CasterClass::Open;
};

}  // namespace penumbra

#endif
