// penumbra::scene weld — vertex ids by position, for adjacency across split vertices (OBJ UV or
// normal seams): bent_normals.hpp's bentNormalMesh takes them as its `weld` array.
//
// Part of penumbra::support (tests, examples). Needs meshoptimizer (Debian libmeshoptimizer-dev):
// link meshoptimizer::meshoptimizer (find_package(meshoptimizer CONFIG)) in the target that
// includes this header; the rest of penumbra::support does not need it.
#ifndef PENUMBRA_SCENE_WELD_HPP
#define PENUMBRA_SCENE_WELD_HPP

#include <penumbra/scene/scene.hpp>

#include <meshoptimizer.h>

#include <cstdint>
#include <vector>

namespace penumbra::scene {

/// weld[v] = the same id for every vertex with bit-identical position (meshopt_generateVertexRemap
/// over the positions alone); ids are < positions.size().
inline std::vector<uint32_t> weldByPosition(const std::vector<glm::vec3>& positions) {
    std::vector<uint32_t> weld(positions.size());
    if (!positions.empty())
        meshopt_generateVertexRemap(weld.data(), nullptr, positions.size(), positions.data(), positions.size(),
                                    sizeof(glm::vec3));
    return weld;
}

}  // namespace penumbra::scene

#endif
