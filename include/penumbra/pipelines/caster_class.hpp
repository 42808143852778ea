// penumbra/pipelines/caster_class.hpp — the class of the casters one call of a pipeline's caster
// callback draws (the hard and the soft pipeline call it once per class and list block).
//   Closed: watertight, edge-manifold meshes, consistently oriented with outward normals (unions of
//           such meshes qualify); the pipelines may cull some of their triangles (§3.3 / §4.3).
//   Open:   everything else (ground planes, foliage cards, meshes with holes).
// scene::Mesh::closed (support code) is a checked way to classify an indexed mesh.
#ifndef PENUMBRA_PIPELINES_CASTER_CLASS_HPP
#define PENUMBRA_PIPELINES_CASTER_CLASS_HPP

namespace penumbra {

enum class CasterClass { Closed, Open };

}  // namespace penumbra

#endif
