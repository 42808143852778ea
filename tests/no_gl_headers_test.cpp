// Every block's GL-free header (pure setup, plans, CPU twins; docs/design.md convention 1) and the
// oracle compile and run with no GL header anywhere in the translation unit — this target has no
// GL loader on its include path, and a GL header slipping in is an #error. (The conservative
// raster header has its own, stricter test: conservative_raster_no_gl_test.)
#include <penumbra/airlight.hpp>
#include <penumbra/bent_normals.hpp>
#include <penumbra/buffer_range.hpp>
#include <penumbra/deep_shadow_map.hpp>
#include <penumbra/influence_region.hpp>
#include <penumbra/light_lut.hpp>
#include <penumbra/light_volume.hpp>
#include <penumbra/light_samples.hpp>
#include <penumbra/penumbra_casting.hpp>
#include <penumbra/adjacency.hpp>
#include <penumbra/pipelines/alias_free_hard.hpp>
#include <penumbra/pipelines/sample_based_soft.hpp>
#include <penumbra/pipelines/silhouette_marks.hpp>
#include <penumbra/reference/compare.hpp>
#include <penumbra/reference/light_samples.hpp>
#include <penumbra/reference/light_shafts.hpp>
#include <penumbra/reference/transmittance.hpp>
#include <penumbra/reference/visibility.hpp>
#include <penumbra/sample_lists.hpp>
#include <penumbra/shadow_edge_stencil.hpp>
#include <penumbra/scan.hpp>

#if defined(GL_VERSION_1_0) || defined(__gl_h_) || defined(__glad_h_) || defined(GLAD_GL_H_) || \
    defined(__gl_glcorearb_h_) || defined(__glext_h_) || defined(__gl_glext_h_) || defined(__EPOXY_GL_H) || \
    defined(PENUMBRA_GL_GL_HPP)
#error a GL-free penumbra header pulled in a GL header
#endif

#include <doctest/doctest.h>

#include <string>
#include <vector>

TEST_CASE("cpu: the GL-free headers plan, validate and run their CPU twins without GL") {
    // Scan: the plan an RHI records, and the twin.
    const penumbra::ScanPlan plan = penumbra::planScan(1u << 20);
    CHECK(plan.dispatches > 0);
    const uint32_t in[5] = {1, 2, 3, 4, 5};
    uint32_t out[5] = {};
    penumbra::scanCpu(in, out, 5, penumbra::ScanKind::Inclusive);
    CHECK(out[4] == 15u);
    // Sample lists: setup, parameter block, twin.
    const penumbra::SampleListsSetup setup = penumbra::sampleListsSetup(8, 8, 2);
    penumbra::SampleListsLight light;
    light.light = glm::vec4(0, 5, 0, 1);
    light.view_projection = penumbra::lightViewProjectionForBounds(light.light, glm::vec3(-1, 0, -1), glm::vec3(1, 0, 1));
    const std::vector<glm::vec4> positions = {{0, 0, 0, 1}, {0.5f, 0, 0.5f, 1}}, normals = {{0, 1, 0, 0}, {0, 1, 0, 0}};
    const penumbra::SampleListsCpu lists = penumbra::buildSampleListsCpu(setup, light, positions.data(), normals.data());
    CHECK(lists.header.accepted == 2u);
    // The hard-shadow twin with a caster over the first sample, and the oracle agreeing.
    const std::vector<glm::vec3> vertices = {{-0.2f, 1, -0.2f}, {0.2f, 1, -0.2f}, {0, 1, 0.3f}};
    const std::vector<uint32_t> indices = {0, 1, 2};
    const std::vector<uint8_t> closed = {0};
    penumbra::AliasFreeHardOptions options;
    options.grid_width = options.grid_height = 8;
    const std::vector<uint32_t> states = penumbra::aliasFreeHardCpu(options, light, positions.data(), normals.data(), 2,
                                                                    {&vertices, &indices, &closed});
    CHECK(states[0] == PENUMBRA_AFH_SHADOWED);
    CHECK(states[1] == PENUMBRA_AFH_LIT);
    const penumbra::reference::VisibilityOracle oracle(vertices, indices);
    const auto c = penumbra::reference::compareHardStates(oracle, positions, states, penumbra::reference::hardLight(light.light));
    CHECK(c.mismatched == 0);
    CHECK(c.samples == 2);
    // Light-sample sets: the oracle's world samples and the LUT's local ones.
    const penumbra::LightSampleSets light_sets = penumbra::makeLightSampleSets(penumbra::Light{});
    CHECK(light_sets.world.size() == light_sets.local.size());
    CHECK(penumbra::lightSampleSet(1, 2, 3, light_sets.sets()) < light_sets.sets());
    // Influence regions: setup and the CPU twin of a small caster under a sphere light.
    penumbra::Light sphere;
    sphere.center = glm::dvec3(0, 5, 0);
    sphere.size = glm::dvec3(0.5);
    penumbra::InfluenceRegionOptions influence;
    influence.grid_width = influence.grid_height = 8;
    influence.far_plane = penumbra::influenceFarPlaneAtDepth(light.view_projection, 6.0);
    const penumbra::InfluenceRegionSetup influence_setup = penumbra::influenceRegionSetup(sphere, light.view_projection, influence);
    const penumbra::InfluenceRegion region = penumbra::influenceRegion(vertices[0], vertices[1], vertices[2], influence_setup);
    CHECK(region.kind == penumbra::InfluenceRegionKind::Hull);
    CHECK(penumbra::influenceRegionCoversTexel(region, 4, 4));
    // Penumbra casting (laine2005) on the CPU: the caster over the first sample blocks part of the
    // sphere light, the same bits as the oracle.
    penumbra::LightSampleOptions few;
    few.count = 32;
    few.sets = 1;
    const penumbra::LightSampleSets sphere_sets = penumbra::makeLightSampleSets(sphere, few);
    penumbra::PenumbraCaster caster({glm::dvec3(0, 0, 0)}, sphere, sphere_sets);
    caster.addTriangle(glm::dvec3(vertices[0]), glm::dvec3(vertices[1]), glm::dvec3(vertices[2]));
    const penumbra::PenumbraCastingResult cast = caster.finish();
    const penumbra::reference::VisibilityResult truth =
        oracle.evaluate({glm::dvec3(0, 0, 0)}, std::vector<glm::dvec3>(sphere_sets.world.begin(), sphere_sets.world.end()));
    CHECK(cast.blocked == truth.blocked);
    CHECK(cast.visibleFraction(0) < 1.0);
    // Status is plain C++ too.
    CHECK(std::string(penumbra::statusName(penumbra::Status::RangeTooSmall)) == "range too small");
}
