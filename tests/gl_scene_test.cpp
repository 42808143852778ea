// The G-buffer helper against the oracle's primary rays: at every pixel centre the rasterised
// surface and the ray-cast surface must agree (same triangle, or a hit at the same point when the
// pixel centre lies on a shared edge), and background must match.
#include <penumbra/reference/visibility.hpp>
#include <penumbra/scene/gl_scene.hpp>

#include "support/gl_test_support.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <cstring>

TEST_CASE("G-buffer view samples match the oracle's primary rays") {
    penumbra::test::context();
    for (const std::string name : {"torus_knot", "columns"}) {
        CAPTURE(name);
        const penumbra::scene::Scene scene = penumbra::scene::builtin(name);
        penumbra::scene::GpuScene gpu(scene);
        const uint32_t w = 96, h = 64;
        penumbra::scene::GBuffer gbuffer(w, h);
        const glm::mat4 view_projection = scene.camera.projection(float(w) / h) * scene.camera.view();
        gbuffer.render(gpu, view_projection);
        const auto positions = gbuffer.positionBuffer().download<glm::vec4>();
        const auto faces = gbuffer.faceBuffer().download<glm::vec4>();
        REQUIRE(positions.size() == size_t(w) * h);

        penumbra::reference::VisibilityOracle oracle(gpu.positions(), gpu.indices());
        const glm::dmat4 inverse = glm::inverse(glm::dmat4(view_projection));
        const glm::dvec3 eye(scene.camera.eye);
        size_t covered = 0, same_triangle = 0, far_apart = 0, coverage_mismatch = 0;
        for (uint32_t y = 0; y < h; ++y) {
            for (uint32_t x = 0; x < w; ++x) {
                const size_t i = size_t(y) * w + x;  // GL rows: bottom first
                const glm::dvec4 ndc((x + 0.5) / w * 2 - 1, (y + 0.5) / h * 2 - 1, 1.0, 1.0);
                const glm::dvec4 far_point = inverse * ndc;
                const glm::dvec3 dir = glm::normalize(glm::dvec3(far_point) / far_point.w - eye);
                const penumbra::reference::Hit hit = oracle.closestHit(eye, dir, 0.0, 1e30);
                const bool gpu_hit = positions[i].w == 1.0f;
                if (hit.hit != gpu_hit) {
                    ++coverage_mismatch;
                    continue;
                }
                if (!hit.hit) continue;
                ++covered;
                uint32_t triangle = 0;
                std::memcpy(&triangle, &faces[i].w, 4);
                if (triangle == hit.triangle) ++same_triangle;
                const glm::dvec3 p = eye + hit.t * dir;
                if (glm::length(p - glm::dvec3(positions[i])) > 1e-3) ++far_apart;
            }
        }
        MESSAGE(name, ": ", covered, " covered pixels, ", same_triangle, " same triangle, ", far_apart,
                " positions > 1e-3 apart, ", coverage_mismatch, " coverage mismatches");
        CHECK(covered > w * h / 4);
        // Pixel centres on shared edges or silhouettes may pick a neighbour: a handful at most.
        CHECK(double(same_triangle) >= 0.97 * covered);
        CHECK(double(far_apart) <= 0.01 * covered);
        CHECK(double(coverage_mismatch) <= 0.01 * w * h);
    }
}
