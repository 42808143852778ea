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

/// A spot light looking down -y over a ground plane (depth 0.9 in its map) with a square caster
/// (depth `caster`, 1 = none) in the middle of its R^2 map.
struct ShaftScene {
    uint32_t r = 64;
    glm::dmat4 view_projection, inverse;
    glm::dvec3 light{0.0, 4.0, 0.0};
    std::vector<float> depth;
};

ShaftScene shaftScene(bool caster) {
    ShaftScene s;
    const glm::dmat4 view = glm::lookAt(s.light, glm::dvec3(0.0), glm::dvec3(0, 0, -1));
    s.view_projection = glm::perspective(glm::radians(60.0), 1.0, 0.5, 10.0) * view;
    s.inverse = glm::inverse(s.view_projection);
    s.depth.assign(size_t(s.r) * s.r, 0.0f);
    // The ground y = 0 ray cast per texel centre (exact plane depths), the caster a square at y = 2.
    for (uint32_t y = 0; y < s.r; ++y) {
        for (uint32_t x = 0; x < s.r; ++x) {
            const double nx = 2.0 * (x + 0.5) / s.r - 1.0, ny = 2.0 * (y + 0.5) / s.r - 1.0;
            const glm::dvec4 a = s.inverse * glm::dvec4(nx, ny, -1, 1), b = s.inverse * glm::dvec4(nx, ny, 1, 1);
            const glm::dvec3 from = glm::dvec3(a) / a.w, to = glm::dvec3(b) / b.w;
            double plane = 0.0;
            if (caster && x >= 24 && x < 40 && y >= 24 && y < 40) plane = 2.0;
            const double t = (plane - from.y) / (to.y - from.y);
            const glm::dvec4 clip = s.view_projection * glm::dvec4(from + t * (to - from), 1.0);
            s.depth[size_t(y) * s.r + x] = float(std::clamp(0.5 * clip.z / clip.w + 0.5, 0.0, 1.0));
        }
    }
    return s;
}

penumbra::AirlightSetup fog() {
    penumbra::AirlightMedium medium;
    medium.sigma_s = 0.08;
    medium.sigma_t = 0.1;
    penumbra::AirlightOptions options;
    options.method = penumbra::AirlightMethod::Quadrature;
    options.quadrature_nodes = 32;
    return penumbra::airlightSetup(medium, 50.0, options);
}

/// Eye rays of a W x H camera at `eye` looking at `target` (45 degrees vertical).
std::vector<glm::dvec3> rays(const glm::dvec3& eye, const glm::dvec3& target, uint32_t w, uint32_t h) {
    const glm::dmat4 inverse = glm::inverse(glm::perspective(glm::radians(45.0), double(w) / h, 0.1, 100.0) *
                                            glm::lookAt(eye, target, glm::dvec3(0, 1, 0)));
    std::vector<glm::dvec3> dirs;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
            const glm::dvec4 p = inverse * glm::dvec4(2.0 * (x + 0.5) / w - 1.0, 2.0 * (y + 0.5) / h - 1.0, 1.0, 1.0);
            dirs.push_back(glm::normalize(glm::dvec3(p) / p.w - eye));
        }
    return dirs;
}

/// Distance along the ray to the ground y = 0 (the scene depth), or `far`.
double groundDepth(const glm::dvec3& eye, const glm::dvec3& dir, double far) {
    return dir.y < 0.0 ? std::min(far, -eye.y / dir.y) : far;
}

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
        const double march = penumbra::reference::rayMarch(
            eye, dir, depth, 20000, [&](const glm::dvec3& x) { return penumbra::reference::shadowMapLit(view, ShadowMapLookup::Lattice, x); },
            [&](double t) { return penumbra::airlightDensity(setup, eye, dir, scene.light, t); });
        worst = std::max(worst, std::abs(volume - march));
        worst_adaptive = std::max(worst_adaptive, std::abs(volume - coarse));
        peak = std::max(peak, volume);
    }
    MESSAGE("96 rays: peak airlight ", peak, ", |static volume - march (20 000 steps)| <= ", worst, ", |adaptive - static| <= ",
            worst_adaptive);
    CHECK(peak > 0.0);
    CHECK(worst <= 2e-3 * peak);           // the midpoint rule's error at the lit boundaries
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
        const double sm = penumbra::reference::rayMarch(
            eye, dir, depth, 2000, [&](const glm::dvec3& x) { return penumbra::reference::shadowMapLit(view, ShadowMapLookup::Nearest, x); },
            density);
        const double exact = penumbra::reference::rayMarch(
            eye, dir, depth, 2000, [&](const glm::dvec3& x) { return penumbra::reference::oracleLit(view, oracle, map.light.position, x); },
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
