// The light-volume render's CPU twin against ray marching (penumbra/reference/light_shafts.hpp,
// billeter2010): the static volume's airlight equals the converged ray march of the same lattice
// surface; the adaptive volume stays next to the static one; a wall in front of the shafts gives the
// image without them (the clamp: hidden crossings cancel); the shadow-map march against exact
// visibility (the oracle) is reported.
#include <penumbra/airlight.hpp>
#include <penumbra/light_volume.hpp>
#include <penumbra/reference/light_shafts.hpp>

#include "support/light_volume_maps.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace {

using penumbra::reference::LightVolumeRaycaster;
using penumbra::reference::ShadowMapLookup;
using penumbra::reference::ShadowMapView;
using penumbra::test::fog;
using penumbra::test::groundDepth;
using penumbra::test::rays;
using penumbra::test::shaftScene;
using penumbra::test::ShaftScene;

}  // namespace

TEST_CASE("light shafts: the static volume's airlight == the converged ray march of its lattice surface") {
    const ShaftScene scene = shaftScene(true);
    const penumbra::AirlightSetup setup = fog();
    penumbra::LightVolumeOptions options;
    options.tessellation = penumbra::LightVolumeTessellation::Static;
    const penumbra::LightVolumeSetup lv = penumbra::lightVolumeSetup(scene.r, options);
    const std::vector<float> corners = penumbra::lightVolumeCornerDepths(lv, scene.depth);
    const LightVolumeRaycaster fixed(penumbra::tessellateLightVolume(lv, corners), corners, scene.inverse, scene.light);
    options.tessellation = penumbra::LightVolumeTessellation::Adaptive;
    options.flatness = 1e-6;
    const penumbra::LightVolumeSetup lva = penumbra::lightVolumeSetup(scene.r, options);
    const LightVolumeRaycaster adaptive(penumbra::tessellateLightVolume(lva, corners), corners, scene.inverse, scene.light);
    ShadowMapView view;
    view.view_projection = scene.view_projection;
    view.resolution = scene.r;
    view.corners = &corners;
    const glm::dvec3 eye(5.0, 1.5, 6.0);
    double worst = 0.0, worst_adaptive = 0.0, peak = 0.0;
    for (const glm::dvec3& dir : rays(eye, glm::dvec3(0.0, 1.0, 0.0), 12, 8)) {
        const double depth = groundDepth(eye, dir, 30.0);
        const auto cumulative = [&](double t) { return penumbra::airlightReference(setup, eye, dir, scene.light, 0.0, t, 1e-12); };
        const double volume = fixed.airlight(eye, dir, depth, 40.0, cumulative);
        const double coarse = adaptive.airlight(eye, dir, depth, 40.0, cumulative);
        const auto [t_in, t_out] = penumbra::reference::frustumInterval(view, eye, dir, depth);
        const double march = penumbra::reference::rayMarch(
            eye, dir, t_in, t_out, 20000, [&](const glm::dvec3& x) { return penumbra::reference::shadowMapLit(view, ShadowMapLookup::Lattice, x); },
            [&](double t) { return penumbra::airlightDensity(setup, eye, dir, scene.light, t); });
        worst = std::max(worst, std::abs(volume - march));
        worst_adaptive = std::max(worst_adaptive, std::abs(volume - coarse));
        peak = std::max(peak, volume);
    }
    MESSAGE("96 rays: peak airlight ", peak, ", |static volume - march (20 000 steps)| <= ", worst, ", |adaptive - static| <= ",
            worst_adaptive);
    CHECK(peak > 0.0);
    CHECK(worst <= 2e-4 * peak);           // the midpoint rule's error at the lit boundaries
    CHECK(worst_adaptive <= 1e-6 * peak);  // 2e-6 in depth moves the boundary by a hair
}

TEST_CASE("light shafts: a wall in front of the shafts gives the image without them (the clamp)") {
    const ShaftScene with = shaftScene(true), without = shaftScene(false);
    const penumbra::AirlightSetup setup = fog();
    penumbra::LightVolumeOptions options;
    options.flatness = 1e-6;
    const penumbra::LightVolumeSetup lv = penumbra::lightVolumeSetup(with.r, options);
    const std::vector<float> corners_with = penumbra::lightVolumeCornerDepths(lv, with.depth);
    const std::vector<float> corners_without = penumbra::lightVolumeCornerDepths(lv, without.depth);
    const LightVolumeRaycaster shafts(penumbra::tessellateLightVolume(lv, corners_with), corners_with, with.inverse, with.light);
    const LightVolumeRaycaster plain(penumbra::tessellateLightVolume(lv, corners_without), corners_without, without.inverse,
                                     without.light);
    // The eye at z = 6 looks towards the shaft (|x|, |z| < 1 around the origin); a wall z = 3 in front.
    const glm::dvec3 eye(0.3, 1.0, 6.0);
    double walled = 0.0, open = 0.0, scale = 0.0;
    for (const glm::dvec3& dir : rays(eye, glm::dvec3(0.0, 1.0, 0.0), 10, 8)) {
        const auto cumulative = [&](double t) { return penumbra::airlightReference(setup, eye, dir, with.light, 0.0, t, 1e-12); };
        const double wall = dir.z < 0.0 ? (3.0 - eye.z) / dir.z : 30.0;
        const double depth = std::min(groundDepth(eye, dir, 30.0), wall);
        walled = std::max(walled, std::abs(shafts.airlight(eye, dir, depth, 40.0, cumulative) - plain.airlight(eye, dir, depth, 40.0, cumulative)));
        const double far = groundDepth(eye, dir, 30.0);
        open = std::max(open, std::abs(shafts.airlight(eye, dir, far, 40.0, cumulative) - plain.airlight(eye, dir, far, 40.0, cumulative)));
        scale = std::max(scale, plain.airlight(eye, dir, far, 40.0, cumulative));
    }
    MESSAGE("80 rays: max |shafts - none| behind a wall ", walled, ", without the wall ", open, " (airlight up to ", scale, ")");
    CHECK(open > 1e-3 * scale);     // the shaft shows without the wall ...
    CHECK(walled <= 1e-12 * scale);  // ... and not at all behind it
}

TEST_CASE("light shafts: ray marching the shadow map against exact visibility (the oracle)") {
    const penumbra::test::SceneMap map = penumbra::test::sceneMap("columns", 256);
    const penumbra::scene::Scene scene = penumbra::scene::builtin("columns");
    const penumbra::scene::Mesh merged = scene.merged();
    const std::vector<glm::dvec3> positions(merged.positions.begin(), merged.positions.end());
    const penumbra::reference::VisibilityOracle oracle(positions, merged.indices);
    penumbra::AirlightMedium medium;
    medium.sigma_s = 0.2;
    medium.sigma_t = 0.25;
    const penumbra::AirlightSetup setup = penumbra::airlightSetup(medium, 20.0);
    ShadowMapView view;
    view.view_projection = map.light.view_projection;
    view.resolution = 256;
    view.depth = &map.depth;
    const glm::dvec3 eye(scene.camera.eye), target(scene.camera.target);
    double sum2 = 0.0, peak = 0.0;
    uint32_t count = 0;
    for (const glm::dvec3& dir : rays(eye, target, 16, 12)) {
        const penumbra::reference::Hit hit = oracle.closestHit(eye, dir, 0.0, 100.0);
        const double depth = hit.hit ? hit.t : 100.0;
        const auto density = [&](double t) { return penumbra::airlightDensity(setup, eye, dir, map.light.position, t); };
        const auto [t_in, t_out] = penumbra::reference::frustumInterval(view, eye, dir, depth);
        const double sm = penumbra::reference::rayMarch(
            eye, dir, t_in, t_out, 2000, [&](const glm::dvec3& x) { return penumbra::reference::shadowMapLit(view, ShadowMapLookup::Nearest, x); },
            density);
        const double exact = penumbra::reference::rayMarch(
            eye, dir, t_in, t_out, 2000, [&](const glm::dvec3& x) { return penumbra::reference::oracleLit(view, oracle, map.light.position, x); },
            density);
        sum2 += (sm - exact) * (sm - exact);
        peak = std::max(peak, exact);
        ++count;
    }
    const double rmse = std::sqrt(sum2 / count);
    MESSAGE("columns, 192 rays, 2000 steps: shadow map (256^2, nearest) vs exact visibility RMSE ", rmse, " (peak ", peak, ")");
    CHECK(peak > 0.0);
    CHECK(rmse <= 0.05 * peak);
}
