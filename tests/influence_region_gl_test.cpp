// GLSL twin of the influence region (shaders/penumbra/influence_region/) against the CPU
// (penumbra/influence_region.hpp): per triangle the kind, the fallback bits and the emitted polygon
// bit for bit (bitwise tier: llvmpipe rounds float operations correctly; elsewhere the vertices
// agree within 1e-3 texel and the coverage assertions hold), GL's rasterization of it == the CPU's pixel-centre rule away from edges, and no
// shadowed receiver's texel left uncovered by the GPU (the never-miss property on the GPU, for a
// subset of the CPU test's cases).
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/shader.hpp>
#include <penumbra/influence_region.hpp>
#include <penumbra/pipelines/alias_free_hard.hpp>

#include "support/gl_test_support.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace {

struct Rng {
    std::mt19937_64 engine;
    explicit Rng(uint64_t seed) : engine(seed) {}
    double uniform(double lo = 0.0, double hi = 1.0) {
        return lo + (hi - lo) * (static_cast<double>(engine() >> 11) * (1.0 / 9007199254740992.0));
    }
    glm::dvec3 sphere() {
        for (;;) {
            const glm::dvec3 v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
            const double l = glm::length(v);
            if (l > 1e-3 && l <= 1.0) return v / l;
        }
    }
};

struct GpuRun {
    std::vector<uint32_t> record, coverage;
};

GpuRun runGpu(const penumbra::InfluenceRegionSetup& setup, const std::vector<glm::vec4>& vertices) {
    penumbra::ShaderDefines defines = setup.defines;
    defines.push_back({"PENUMBRA_INFLUENCE_RECORD", "1"});
    const penumbra::gl::Program program =
        penumbra::gl::buildProgram({"penumbra/conservative_raster/conservative_raster.vert.glsl",
                                    "penumbra/influence_region/influence_region.geom.glsl",
                                    "penumbra/influence_region/influence_region.frag.glsl"},
                                   defines);
    const size_t triangles = vertices.size() / 3;
    const size_t words = 1 + (size_t(setup.width()) * setup.height() + 31) / 32;
    penumbra::gl::Buffer vbo = penumbra::gl::Buffer::fromVector(vertices);
    penumbra::gl::Buffer params(sizeof(setup.params), &setup.params);
    penumbra::gl::Buffer record(triangles * PENUMBRA_INFLUENCE_RECORD_WORDS * 4);
    record.fill(0xffffffffu);  // poison
    penumbra::gl::Buffer coverage(triangles * words * 4);
    coverage.fill(0u);
    GLuint vao = 0, fbo = 0;
    glCreateVertexArrays(1, &vao);
    glVertexArrayVertexBuffer(vao, 0, vbo.id(), 0, sizeof(glm::vec4));
    glVertexArrayAttribFormat(vao, 0, 4, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(vao, 0, 0);
    glEnableVertexArrayAttrib(vao, 0);
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferParameteri(fbo, GL_FRAMEBUFFER_DEFAULT_WIDTH, setup.width());
    glNamedFramebufferParameteri(fbo, GL_FRAMEBUFFER_DEFAULT_HEIGHT, setup.height());
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, setup.width(), setup.height());
    glDisable(GL_CULL_FACE);
    glDisable(GL_DEPTH_TEST);
    glBindVertexArray(vao);
    program.use();
    glUniform1ui(8, 0u);
    glUniform2i(9, 0, 0);
    glUniform2ui(10, static_cast<GLuint>(setup.width()), static_cast<GLuint>(setup.height()));
    glBindBufferBase(GL_UNIFORM_BUFFER, PENUMBRA_INFLUENCE_PARAMS_BINDING, params.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_INFLUENCE_COVERAGE_BINDING, coverage.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_INFLUENCE_RECORD_BINDING, record.id());
    glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(vertices.size()));
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    GpuRun out;
    out.record = record.download<uint32_t>();
    out.coverage = coverage.download<uint32_t>();
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glBindVertexArray(0);
    glDeleteFramebuffers(1, &fbo);
    glDeleteVertexArrays(1, &vao);
    penumbra::gl::checkErrors("influence region");
    return out;
}

}  // namespace

TEST_CASE("GPU: influence regions == the CPU twin bit for bit, GL coverage == the pixel rule, no shadowed texel missed") {
    penumbra::test::context();
    Rng rng(penumbra::test::testSeed());
    long compared = 0, polygon_mismatch = 0, kind_mismatch = 0, coverage_missing = 0, coverage_extra = 0, shadowed = 0,
         gpu_misses = 0, whole = 0, hulls = 0;
    double polygon_max_px = 0.0;  // largest |GPU - CPU| of a polygon vertex, texels
    for (int sides : {4, 6, 8, 12}) {
        for (int cut = 0; cut < 2; ++cut) {
            CAPTURE(sides);
            CAPTURE(cut);
            penumbra::Light light;
            light.shape = cut ? penumbra::LightShape::Ellipsoid : penumbra::LightShape::Sphere;
            light.center = glm::dvec3(0.25, 6.0, -0.5);
            light.size = glm::dvec3(0.6, 0.4, 0.5);
            light.axis_z = glm::dvec3(0.2, 1.0, 0.1);
            const glm::vec3 lo(-4, 0, -4), hi(4, 1, 4);
            const glm::mat4 vp = penumbra::lightViewProjectionForBounds(glm::vec4(glm::vec3(light.center), 1.0f), lo, hi);
            penumbra::InfluenceRegionOptions o;
            o.grid_width = 96;
            o.grid_height = 64;
            o.sides = sides;
            o.cut_by_supporting_plane = cut != 0;
            o.far_plane = penumbra::influenceFarPlaneAtDepth(vp, 7.5);
            const penumbra::InfluenceRegionSetup setup = penumbra::influenceRegionSetup(light, vp, o);
            const penumbra::LightFrame frame = penumbra::lightFrame(light);
            // Triangles between the light and the ground: small, large, slivers, near the light.
            std::vector<glm::vec4> vertices;
            const int count = 256;
            for (int t = 0; t < count; ++t) {
                const int family = t % 4;
                const glm::dvec3 base(rng.uniform(-4, 4), rng.uniform(0.5, 5.0), rng.uniform(-4, 4));
                const double size = family == 1 ? 2.0 : family == 3 ? 0.02 : 0.3;
                glm::dvec3 v[3] = {base, base + size * rng.sphere(), base + size * rng.sphere()};
                if (family == 2) v[2] = v[0] + 0.5 * (v[1] - v[0]) + 1e-6 * rng.sphere();  // sliver
                if (t % 32 == 5) v[0] = light.center + glm::dvec3(0.3, -0.65, 0.2);      // near the light
                for (const auto& x : v) vertices.emplace_back(glm::vec3(x), 1.0f);
            }
            const GpuRun gpu = runGpu(setup, vertices);
            const size_t words = 1 + (size_t(setup.width()) * setup.height() + 31) / 32;
            for (int t = 0; t < count; ++t) {
                const glm::vec3 a(vertices[3 * t]), b(vertices[3 * t + 1]), c(vertices[3 * t + 2]);
                const penumbra::InfluenceRegion r = penumbra::influenceRegion(a, b, c, setup);
                const uint32_t* rec = &gpu.record[size_t(t) * PENUMBRA_INFLUENCE_RECORD_WORDS];
                ++compared;
                whole += r.kind == penumbra::InfluenceRegionKind::WholeGrid;
                hulls += r.kind == penumbra::InfluenceRegionKind::Hull;
                // The kind and count decide how the record is read: a triangle whose kind differs (a
                // driver rounding a threshold the other way) is compared for never-miss alone.
                const bool kind_same = rec[0] == uint32_t(r.kind) && rec[1] == r.fallback && rec[2] == uint32_t(r.count);
                if (!kind_same && ++kind_mismatch <= 5)
                    MESSAGE("triangle ", t, ": GPU kind ", rec[0], " fallback ", rec[1], " count ", rec[2], ", CPU ", int(r.kind),
                            " ", r.fallback, " ", r.count);
                const uint32_t* cov = &gpu.coverage[size_t(t) * words];
                auto gpuCovers = [&](int x, int y) {
                    const size_t i = size_t(y) * setup.width() + x;
                    return (cov[1 + i / 32] >> (i % 32)) & 1u;
                };
                if (kind_same) {
                    bool same = true;
                    for (int i = 0; i < r.count; ++i) {
                        uint32_t bx, by;
                        std::memcpy(&bx, &r.pixels[i].x, 4);
                        std::memcpy(&by, &r.pixels[i].y, 4);
                        same = same && rec[4 + 2 * i] == bx && rec[5 + 2 * i] == by;
                        float gx, gy;
                        std::memcpy(&gx, &rec[4 + 2 * i], 4);
                        std::memcpy(&gy, &rec[5 + 2 * i], 4);
                        const double d = std::max(std::abs(double(gx) - r.pixels[i].x), std::abs(double(gy) - r.pixels[i].y));
                        polygon_max_px = std::max(polygon_max_px, std::isfinite(d) ? d : 1e30);
                    }
                    if (!same && ++polygon_mismatch <= 5) MESSAGE("triangle ", t, ": polygon bits differ");
                    // Coverage: every texel the CPU rule predicts away from edges (0.01 texel) is a GPU
                    // fragment and the GPU has no fragment the rule excludes away from edges.
                    const penumbra::HullRaster expected = penumbra::influenceRegionTexels(r, setup, 0.01);
                    std::vector<uint8_t> state(size_t(setup.width()) * setup.height(), 0);
                    for (const auto& p : expected.fragments) {
                        state[size_t(p.y) * setup.width() + p.x] = 1;
                        if (!gpuCovers(p.x, p.y)) ++coverage_missing;
                    }
                    for (const auto& p : expected.uncertain) state[size_t(p.y) * setup.width() + p.x] = 2;
                    for (int y = 0; y < setup.height(); ++y)
                        for (int x = 0; x < setup.width(); ++x)
                            if (gpuCovers(x, y) && state[size_t(y) * setup.width() + x] == 0) ++coverage_extra;
                }
                // Never miss, on the GPU's coverage: shadowed receivers from the light's boundary.
                const glm::dvec3 la = frame.toLocal(glm::dvec3(a)), lb = frame.toLocal(glm::dvec3(b)),
                                 lc = frame.toLocal(glm::dvec3(c));
                for (int i = 0; i < 16; ++i) {
                    const glm::dvec3 y = rng.sphere();
                    const double u = rng.uniform(), w = rng.uniform(), su = std::sqrt(u);
                    const glm::dvec3 x = (1 - su) * la + su * (1 - w) * lb + su * w * lc;
                    const glm::dvec3 world = frame.toWorld(y + rng.uniform(1.0, 4.0) * (x - y));
                    const glm::dvec3 pix = penumbra::influenceProjectPixel(setup, world);
                    const glm::dvec4 fl = setup.far_plane_local;
                    const glm::dvec3 ql = setup.frame.toLocal(world);
                    if (!(glm::dot(glm::dvec3(fl), ql) + fl.w <= 0.0) || !(pix.z > 0.0)) continue;
                    if (!(pix.x >= 0 && pix.x < setup.width() && pix.y >= 0 && pix.y < setup.height())) continue;
                    if (!penumbra::influenceShadowedContinuous(frame, glm::dvec3(a), glm::dvec3(b), glm::dvec3(c), world)) continue;
                    ++shadowed;
                    if (!gpuCovers(int(pix.x), int(pix.y))) ++gpu_misses;
                }
            }
        }
    }
    MESSAGE(compared, " triangles compared (", hulls, " hulls, ", whole, " whole-grid); kind/count mismatches ", kind_mismatch,
            ", polygon bit mismatches ", polygon_mismatch, "; coverage missing ", coverage_missing, ", extra ", coverage_extra,
            "; ", shadowed, " shadowed receivers, GPU misses ", gpu_misses);
    MESSAGE("largest polygon vertex difference GPU - CPU: ", polygon_max_px, " texels");
    CHECK(compared == 4 * 2 * 256);
    PENUMBRA_CHECK_BITWISE("influence region kind/count GPU == CPU twin", kind_mismatch == 0);
    PENUMBRA_CHECK_BITWISE("influence region polygon GPU == CPU twin bit for bit", polygon_mismatch == 0);
    // Portable: a kind flip at a threshold is rare (bound: 1%); vertices agree to far below the
    // 0.01-texel margin of the coverage rule, which is what makes the coverage checks portable.
    CHECK(kind_mismatch * 100 <= compared);
    CHECK(polygon_max_px <= 1e-3);
    CHECK(coverage_missing == 0);
    CHECK(coverage_extra == 0);
    CHECK(gpu_misses == 0);
    CHECK(shadowed > 1000);
    CHECK(hulls > 500);
}
