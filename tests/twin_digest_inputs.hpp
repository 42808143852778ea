// Inputs of tests/twin_digest.cpp. Generated in their own translation unit, which CMake always
// compiles with -ffp-contract=off (also in the contracting build): both builds must hash the twins'
// outputs on bit-identical inputs, and generating random points (lo + (hi - lo) * u, a + u (b - a)
// + v (c - a), glm::lookAt ...) is itself contractible.
#ifndef PENUMBRA_TESTS_TWIN_DIGEST_INPUTS_HPP
#define PENUMBRA_TESTS_TWIN_DIGEST_INPUTS_HPP

#include <penumbra/conservative_raster.hpp>
#include <penumbra/influence_region.hpp>
#include <penumbra/sample_lists.hpp>

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace twin_digest {

/// A small random scene: ground grid + floating triangles, view samples on them.
struct Scene {
    std::vector<glm::vec3> positions;
    std::vector<uint32_t> indices;
    std::vector<uint8_t> closed;      // one per triangle (all open)
    std::vector<glm::vec4> samples;   // view samples (w = 1; some w = 0: background)
    std::vector<glm::vec4> normals;
};

Scene makeScene(uint64_t seed, uint32_t sample_count);
/// Two point lights and a directional one, each with lightViewProjectionForBounds of the samples.
std::vector<penumbra::SampleListsLight> lights(const Scene& scene);

struct DepthInput {
    penumbra::SampleListsView view;  // inverse_view_projection filled, depth_zero_to_one false
    std::vector<float> depth;
    std::vector<glm::vec4> normals;
};
DepthInput makeDepthInput(uint64_t seed);

/// sampleListsParams computed here (contraction off), so a twin's kernel can be checked on
/// identical parameters; and the §4.3 fit keys of the buffer input.
penumbra::SampleListsParams fixedParams(const penumbra::SampleListsSetup& setup, const penumbra::SampleListsLight& light,
                                        const penumbra::SampleListsOptions& options,
                                        const penumbra::SampleListsView* view = nullptr);
penumbra::SampleListsHeader fixedFitKeys(const penumbra::SampleListsSetup& setup, const penumbra::SampleListsLight& light,
                                         const Scene& scene);

/// Random clip-space triangles: small, large, crossing the near plane, thin (in turn).
std::vector<glm::vec4> makeClipTriangles(uint64_t seed, int count);
/// conservativeHull of each triangle, computed here (contraction off).
std::vector<penumbra::ConservativeHull> fixedHulls(const std::vector<glm::vec4>& clips,
                                                   const penumbra::ConservativeRasterSetup& setup);
/// Random pixels (x < 96, y < 64) for the polygon predicate.
std::vector<glm::ivec2> makePixels(uint64_t seed, int count);

/// Blocker-test cases: a, b, c, p, l per case (p on the triangle for every 8th).
std::vector<glm::dvec3> makeBlockerCases(uint64_t seed, int count);
/// Segments (receiver, light point) over the scene, every 4th receiver on a caster.
std::vector<glm::dvec3> makeSegments(const Scene& scene, uint64_t seed, int count);
/// Primary rays (origin, direction).
std::vector<glm::dvec3> makeRays(uint64_t seed, int count);
/// Receivers on the ground and samples of a light.
std::vector<glm::dvec3> makePoints(uint64_t seed, int count, const glm::dvec3& lo, const glm::dvec3& hi);

/// Influence regions: setups (k = 4, 6, 8, 12; cut on and off; sphere, ellipsoid, disk lights)
/// built here, with contraction off (the setup's double arithmetic and the light view-projection
/// are contractible; only this translation unit calls influenceRegionSetup, so only its code for
/// it is linked), and world-space caster triangles for each (3 vertices per triangle).
struct InfluenceInput {
    penumbra::InfluenceRegionSetup setup;
    std::vector<glm::vec3> triangles;
};
std::vector<InfluenceInput> makeInfluenceInputs(uint64_t seed, int triangles_per_setup);

}  // namespace twin_digest

#endif
