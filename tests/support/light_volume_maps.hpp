// Test helper: shadow maps for the light-volume tests — a synthetic light over the unit square
// and the built-in scenes' depth maps, ray cast with the oracle (texel centres, post-projective
// depth in [0, 1], 1 where nothing is hit), and a synthetic shaft scene (a square caster over the
// ground under a spot light) with a camera and a fog for the render tests; volumeSetup() for short.
#ifndef PENUMBRA_TESTS_LIGHT_VOLUME_MAPS_HPP
#define PENUMBRA_TESTS_LIGHT_VOLUME_MAPS_HPP

#include <penumbra/airlight.hpp>
#include <penumbra/light_volume.hpp>
#include <penumbra/pipelines/alias_free_hard.hpp>
#include <penumbra/reference/visibility.hpp>
#include <penumbra/scene/scene.hpp>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

namespace penumbra::test {

/// lightVolumeSetup(r) with the given flatness and tessellation.
inline LightVolumeSetup volumeSetup(uint32_t r, double flatness, LightVolumeTessellation mode = LightVolumeTessellation::Adaptive) {
    LightVolumeOptions options;
    options.flatness = flatness;
    options.tessellation = mode;
    return lightVolumeSetup(r, options);
}

/// A light looking down -y at the unit square, for synthetic maps.
struct TestLight {
    glm::dmat4 view_projection, inverse;
    glm::dvec3 position;
};

inline TestLight testLight() {
    TestLight light;
    light.position = glm::dvec3(0.3, 4.0, -0.2);
    const glm::dmat4 view = glm::lookAt(light.position, glm::dvec3(0.0), glm::dvec3(0, 0, 1));
    light.view_projection = glm::perspective(glm::radians(50.0), 1.0, 0.5, 10.0) * view;
    light.inverse = glm::inverse(light.view_projection);
    return light;
}

/// Texel (x, y)'s centre in NDC -> the oracle's first hit -> post-projective depth in [0, 1]
/// (1: nothing before the far plane), on every thread.
inline std::vector<float> rayCastDepth(const penumbra::reference::VisibilityOracle& oracle, const glm::dmat4& view_projection, uint32_t r) {
    const glm::dmat4 inverse = glm::inverse(view_projection);
    std::vector<float> depth(size_t(r) * r, 1.0f);
    const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t) {
        pool.emplace_back([&, t] {
            for (uint32_t y = t; y < r; y += threads) {
                for (uint32_t x = 0; x < r; ++x) {
                    const double nx = 2.0 * (x + 0.5) / r - 1.0, ny = 2.0 * (y + 0.5) / r - 1.0;
                    glm::dvec4 a = inverse * glm::dvec4(nx, ny, -1.0, 1.0), b = inverse * glm::dvec4(nx, ny, 1.0, 1.0);
                    const glm::dvec3 from = glm::dvec3(a) / a.w, to = glm::dvec3(b) / b.w;
                    const penumbra::reference::Hit hit = oracle.closestHit(from, to - from, 0.0, 1.0);
                    if (!hit.hit) continue;
                    const glm::dvec4 clip = view_projection * glm::dvec4(from + hit.t * (to - from), 1.0);
                    depth[size_t(y) * r + x] = float(std::clamp(0.5 * clip.z / clip.w + 0.5, 0.0, 1.0));
                }
            }
        });
    }
    for (std::thread& thread : pool) thread.join();
    return depth;
}

struct SceneMap {
    std::string name;
    std::vector<float> depth;
    TestLight light;
};

inline SceneMap sceneMap(const std::string& name, uint32_t r) {
    const penumbra::scene::Scene scene = penumbra::scene::builtin(name);
    const penumbra::scene::Mesh merged = scene.merged();
    std::vector<glm::dvec3> positions(merged.positions.begin(), merged.positions.end());
    const penumbra::reference::VisibilityOracle oracle(positions, merged.indices);
    // The spot light frames the casters and the ground around them (1.5x their box).
    penumbra::scene::Bounds box;
    for (size_t m = scene.meshes.size() > 1 ? 1 : 0; m < scene.meshes.size(); ++m) box.extend(scene.meshes[m].bounds());
    const glm::vec3 centre = box.center(), half = 0.75f * (box.max - box.min);
    box.min = centre - half;
    box.max = centre + half;
    SceneMap map;
    map.name = name;
    map.light.position = glm::dvec3(scene.light.position);
    map.light.view_projection =
        glm::dmat4(penumbra::lightViewProjectionForBounds(glm::vec4(scene.light.position, 1.0f), box.min, box.max));
    map.light.inverse = glm::inverse(map.light.view_projection);
    map.depth = rayCastDepth(oracle, map.light.view_projection, r);
    return map;
}

/// A spot light looking down -y over a ground plane (depth 0.9 in its map) with a square caster
/// (depth `caster`, 1 = none) in the middle of its R^2 map.
struct ShaftScene {
    uint32_t r = 64;
    glm::dmat4 view_projection, inverse;
    glm::dvec3 light{0.0, 4.0, 0.0};
    std::vector<float> depth;
};

inline ShaftScene shaftScene(bool caster) {
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

inline penumbra::AirlightSetup fog() {
    penumbra::AirlightMedium medium;
    medium.sigma_s = 0.08;
    medium.sigma_t = 0.1;
    penumbra::AirlightOptions options;
    options.method = penumbra::AirlightMethod::Quadrature;
    options.quadrature_nodes = 32;
    return penumbra::airlightSetup(medium, 50.0, options);
}

/// A W x H camera at `eye` looking at `target` (45 degrees vertical, near 0.1, far 100).
inline glm::dmat4 cameraViewProjection(const glm::dvec3& eye, const glm::dvec3& target, uint32_t w, uint32_t h) {
    return glm::perspective(glm::radians(45.0), double(w) / h, 0.1, 100.0) * glm::lookAt(eye, target, glm::dvec3(0, 1, 0));
}

/// Its pixel-centre rays (unit, row-major from the bottom row), as the GPU render forms them.
inline std::vector<glm::dvec3> rays(const glm::dvec3& eye, const glm::dvec3& target, uint32_t w, uint32_t h) {
    const glm::dmat4 inverse = glm::inverse(cameraViewProjection(eye, target, w, h));
    std::vector<glm::dvec3> dirs;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
            const glm::dvec4 p = inverse * glm::dvec4(2.0 * (x + 0.5) / w - 1.0, 2.0 * (y + 0.5) / h - 1.0, 1.0, 1.0);
            dirs.push_back(glm::normalize(glm::dvec3(p) / p.w - eye));
        }
    return dirs;
}

/// Distance along the ray to the ground y = 0 (the scene depth), or `far`.
inline double groundDepth(const glm::dvec3& eye, const glm::dvec3& dir, double far) {
    return dir.y < 0.0 ? std::min(far, -eye.y / dir.y) : far;
}

}  // namespace penumbra::test

#endif
