// Deep shadow maps on the GPU (penumbra/gl/deep_shadow_map.hpp) against the CPU twin
// (penumbra/deep_shadow_map.hpp): the sorted fragment lists, every level's offsets and vertices,
// and batch lookups, bit for bit on drivers with correctly rounded float32 (the bitwise tier:
// llvmpipe). The portable tier asserts what any driver must reproduce: no overflow, every GPU
// function non-increasing, fragments that agree with the twin's but for edge coverage (counts,
// list lengths and (list, triangle) pairs within 0.1% + 8; matched depths and opacities within
// rounding), and every GPU texel within the compression bound of the twin built from the GPU's
// own fragments (merge, compression and mips checked apart from rasterization, whose edge coverage
// and depth rounding GL leaves to the driver). Scenes: small hairball and grass (built in), grey,
// coloured, per-triangle and per-vertex opacity, box and Gaussian filters, the full mip chain.
#include <penumbra/deep_shadow_map.hpp>
#include <penumbra/gl/deep_shadow_map.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/scene/scene.hpp>

#include "support/gl_test_support.hpp"
#include "support/gl_world.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstring>
#include <random>
#include <vector>

namespace {

using penumbra::DsmFragment;
using penumbra::DsmFragmentsCpu;
using penumbra::DsmLight;
using penumbra::DsmMapCpu;
using penumbra::DsmOpacity;
using penumbra::DsmOptions;

uint32_t bits(float f) {
    uint32_t b;
    std::memcpy(&b, &f, 4);
    return b;
}

using Casters = penumbra::test::SceneCasters;

Casters objects(const penumbra::scene::Scene& scene) { return penumbra::test::castersWithoutGround(scene); }

DsmLight lightFor(const Casters& c) {
    penumbra::scene::Bounds b;
    for (const auto& p : c.positions) b.extend(p);
    const glm::vec3 centre = b.center();
    const float radius = 0.5f * glm::length(b.size());
    const glm::vec3 eye = centre + glm::normalize(glm::vec3(0.3f, 1.0f, 0.2f)) * (3.0f * radius);
    const float dist = glm::length(eye - centre);
    DsmLight light;
    light.view = glm::lookAt(eye, centre, glm::vec3(0.0f, 0.0f, 1.0f));
    light.projection = glm::perspective(2.0f * std::asin(radius / dist), 1.0f, dist - 1.1f * radius, dist + 1.1f * radius);
    return light;
}

/// deepShadowMapSetup of an R x R map of S sub-samples per texel with `levels` levels (0: the whole
/// chain), `channels` and `tolerance` (0: the default 1 / (2 S)); the other options at defaults.
penumbra::DsmSetup setupOf(uint32_t R, uint32_t S, uint32_t levels, uint32_t channels = 1, float tolerance = 0.0f) {
    DsmOptions o;
    o.resolution = R;
    o.samples = S;
    o.levels = levels;
    o.channels = channels;
    o.tolerance = tolerance;
    return penumbra::deepShadowMapSetup(o);
}

/// The GPU side of an opacity hook: the builder's shader library (the default hook or a replaced
/// one) and the texture the default hook reads (0: none).
struct HookGpu {
    const penumbra::ShaderLibrary* library = nullptr;
    GLuint texture = 0;
};

struct Run {
    DsmFragmentsCpu gpu_fragments;
    DsmMapCpu gpu_map;
    penumbra::gl::DsmStatus status;
};

Run runGpu(const penumbra::DsmSetup& setup, const DsmLight& light, const DsmOpacity& opacity, const Casters& c,
           penumbra::gl::DsmCapacity capacity = {}, const penumbra::DsmMedium& medium = {}, const HookGpu& hook = {}) {
    penumbra::gl::DeepShadowMapBuilder builder(setup, capacity,
                                               hook.library ? *hook.library : penumbra::ShaderLibrary::embedded());
    penumbra::gl::Buffer positions = penumbra::gl::Buffer::fromVector(c.positions);
    penumbra::gl::Buffer indices = penumbra::gl::Buffer::fromVector(c.indices);
    penumbra::gl::Buffer vertex_opacity = penumbra::gl::Buffer::fromVector(opacity.per_vertex);
    penumbra::gl::Buffer hook_attribute = penumbra::gl::Buffer::fromVector(opacity.hook_attribute);
    std::vector<glm::vec4> tri;
    for (const auto& a : opacity.per_triangle) tri.emplace_back(a, 0.0f);
    penumbra::gl::Buffer triangle_opacity = penumbra::gl::Buffer::fromVector(tri);
    penumbra::gl::DsmCasterBuffers casters;
    casters.positions = {positions.id(), 0, positions.size()};
    casters.indices = {indices.id(), 0, indices.size()};
    casters.index_count = static_cast<uint32_t>(c.indices.size());
    if (!opacity.per_vertex.empty()) casters.vertex_opacity = {vertex_opacity.id(), 0, vertex_opacity.size()};
    if (!opacity.per_triangle.empty()) casters.triangle_opacity = {triangle_opacity.id(), 0, triangle_opacity.size()};
    if (opacity.hook) {
        casters.opacity_hook = true;
        casters.hook_attribute = {hook_attribute.id(), 0, hook_attribute.size()};
        casters.opacity_texture = hook.texture;
    }
    // Poison the outputs first: nothing may survive from before the build.
    const uint32_t poison = 0xDEADBEEFu;
    glClearNamedBufferData(builder.vertices().buffer, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &poison);
    glClearNamedBufferData(builder.offsets().buffer, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &poison);
    builder.build(light, opacity, casters, medium);
    glFinish();
    REQUIRE(glGetError() == GL_NO_ERROR);
    Run r;
    r.status = builder.readStatus();
    r.gpu_fragments = builder.readFragments();
    r.gpu_map = builder.readMap();
    return r;
}

/// Edge slack for fragment counts: how many fragments may be present on one side only. Which
/// sub-samples a triangle covers at its edges is a float decision (clip-space vertices, edge
/// functions, perspective divide) that GL does not specify bit for bit and a driver may fuse; a
/// sub-sample within rounding of an edge moves to the neighbour triangle, or to none. 0.1% of the
/// fragments plus 8 (small scenes) bounds that; a wrong coverage rule misses whole triangles.
uint64_t edgeSlack(uint64_t fragments) { return fragments / 1000 + 8; }

/// Bound on the L-infinity distance of level `level` of two maps compressed from the same
/// fragments: each is within eps_0 + ... + eps_level of the exact average of its level-0 block
/// (the compressor's bound per level, accumulated over the mip chain: deep_shadow_map.hpp), so two
/// of them are within twice that of each other; 1e-3 covers the float rounding of the merge (FMA,
/// division, flushed denormals) that makes the two merged inputs differ.
double sameFragmentsBound(const penumbra::DsmSetup& setup, uint32_t level) {
    double eps = 0.0;
    for (uint32_t k = 0; k <= level; ++k) eps += setup.levelTolerance(k);
    return 2.0 * eps + 1e-3;
}

/// The fragments of two builds matched by (sub-sample list, triangle): a triangle covers a
/// sub-sample at most once, so the pair names a fragment. A matched pair differs when its depth
/// differs by more than 1e-5 relative or an opacity channel by more than 1e-3: more than the
/// rounding of the perspective-correct interpolation (NVIDIA H200: 1.35e-7 and 6e-8 at worst), as
/// when a hook's texel or stripe boundary is crossed by rounding; such pairs count as edge cases.
struct FragmentMatch {
    uint64_t only_cpu = 0, only_gpu = 0, differ = 0;
    double worst_depth = 0.0, worst_alpha = 0.0;  ///< over matched pairs: relative depth, opacity
};

FragmentMatch matchFragments(const DsmFragmentsCpu& cpu, const DsmFragmentsCpu& gpu, uint32_t channels) {
    FragmentMatch m;
    for (size_t k = 0; k + 1 < cpu.offsets.size(); ++k) {
        uint64_t matched = 0;
        for (uint32_t i = cpu.offsets[k]; i < cpu.offsets[k + 1]; ++i) {
            const DsmFragment& a = cpu.fragments[i];
            const DsmFragment* b = nullptr;
            for (uint32_t j = gpu.offsets[k]; j < gpu.offsets[k + 1] && !b; ++j)
                if (gpu.fragments[j].triangle == a.triangle) b = &gpu.fragments[j];
            if (!b) {
                ++m.only_cpu;
                continue;
            }
            ++matched;
            const double dz = std::fabs(double(a.z) - b->z) / std::max(std::fabs(double(a.z)), 1e-30);
            double da = 0.0;
            for (uint32_t c = 0; c < channels; ++c) da = std::max(da, std::fabs(double(a.alpha[c]) - b->alpha[c]));
            m.differ += !(dz <= 1e-5 && da <= 1e-3);
            m.worst_depth = std::max(m.worst_depth, dz);
            m.worst_alpha = std::max(m.worst_alpha, da);
        }
        m.only_gpu += (gpu.offsets[k + 1] - gpu.offsets[k]) - matched;
    }
    return m;
}

void compareRun(const penumbra::DsmSetup& setup, const DsmLight& light, const DsmOpacity& opacity, const Casters& c,
                const penumbra::DsmMedium& medium = {}, const HookGpu& hook = {}) {
    const DsmFragmentsCpu cpu_fragments = penumbra::buildDsmFragmentsCpu(setup, light, c.positions, c.indices, opacity);
    const DsmMapCpu cpu_map = penumbra::buildDsmMapCpu(setup, cpu_fragments, true, light, medium);
    const Run gpu = runGpu(setup, light, opacity, c, {}, medium, hook);
    // The twin built from the GPU's own fragments: the merge, compression and mip stages checked
    // apart from rasterization, whose edge coverage GL leaves to the driver.
    const DsmMapCpu gpu_twin = penumbra::buildDsmMapCpu(setup, gpu.gpu_fragments, true, light, medium);
    CHECK(gpu.status.fragment_overflow == 0);
    CHECK(gpu.status.vertex_overflow == 0);
    const uint64_t cpu_count = cpu_fragments.fragments.size(), gpu_count = gpu.status.fragments;
    MESSAGE("fragments ", cpu_count, " (GPU ", gpu_count, "), level-0 vertices ", cpu_map.vertexCount(0), " (GPU ",
            gpu.gpu_map.vertexCount(0), ", twin of the GPU's fragments ", gpu_twin.vertexCount(0), ")");
    REQUIRE(gpu.gpu_fragments.offsets.size() == cpu_fragments.offsets.size());
    CHECK(gpu.gpu_fragments.fragments.size() == gpu_count);

    // Fragments. Portable: counts, list lengths and (list, triangle) pairs agree but for the edge
    // slack; matched fragments have the same depth and opacity but for rounding. Bitwise: the same
    // records in the same order.
    const uint64_t slack = edgeSlack(cpu_count);
    CHECK((gpu_count > cpu_count ? gpu_count - cpu_count : cpu_count - gpu_count) <= slack);
    PENUMBRA_CHECK_BITWISE("deep shadow map: fragment count == buildDsmFragmentsCpu's", gpu_count == cpu_count);
    uint64_t list_mismatch = 0;
    for (size_t k = 0; k + 1 < cpu_fragments.offsets.size(); ++k)
        list_mismatch += (cpu_fragments.offsets[k + 1] - cpu_fragments.offsets[k]) !=
                         (gpu.gpu_fragments.offsets[k + 1] - gpu.gpu_fragments.offsets[k]);
    CHECK(list_mismatch <= slack);
    PENUMBRA_CHECK_BITWISE("deep shadow map: sorted fragment lists == buildDsmFragmentsCpu", list_mismatch == 0);
    const FragmentMatch match = matchFragments(cpu_fragments, gpu.gpu_fragments, setup.channels);
    MESSAGE("fragments on one side only: ", match.only_cpu, " CPU, ", match.only_gpu, " GPU; matched but differing ",
            match.differ, " (worst depth ", match.worst_depth, " relative, opacity ", match.worst_alpha, "); slack ", slack);
    // Twice the slack: a sub-sample that changes triangle at an edge is a fragment on each side.
    CHECK(match.only_cpu + match.only_gpu + match.differ <= 2 * slack);
    if (list_mismatch == 0 && gpu.gpu_fragments.fragments.size() == cpu_count) {
        uint64_t record_mismatch = 0;
        for (size_t i = 0; i < cpu_fragments.fragments.size(); ++i) {
            const auto& a = cpu_fragments.fragments[i];
            const auto& b = gpu.gpu_fragments.fragments[i];
            bool same = bits(a.z) == bits(b.z) && a.triangle == b.triangle && bits(a.alpha.x) == bits(b.alpha.x);
            if (setup.channels == 3) same = same && bits(a.alpha.y) == bits(b.alpha.y) && bits(a.alpha.z) == bits(b.alpha.z);
            record_mismatch += !same;
        }
        PENUMBRA_CHECK_BITWISE("deep shadow map: fragment records (depth, triangle, opacity) == the twin's",
                               record_mismatch == 0);
    }

    // Every level. Portable: monotone, and within sameFragmentsBound of the twin of the GPU's own
    // fragments. Bitwise: offsets and vertices == the CPU twin's bit for bit, and within 2 eps + 1e-3
    // of it: that needs the same fragments bit for bit, since a fragment on one side only moves a
    // texel's function by up to its whole opacity, and a depth one ulp off moves a step, across
    // which the L-infinity distance is the step's height (0.9 with S = 1 on an NVIDIA H200).
    const uint32_t F = setup.vertexFloats();
    for (uint32_t l = 0; l < setup.levels; ++l) {
        CAPTURE(l);
        const auto& co = cpu_map.offsets[l];
        const auto& go = gpu.gpu_map.offsets[l];
        const auto& to = gpu_twin.offsets[l];
        REQUIRE(co.size() == go.size());
        REQUIRE(to.size() == go.size());
        uint64_t offset_mismatch = 0, vertex_mismatch = 0, not_monotone = 0;
        double worst_cpu = 0.0, worst_twin = 0.0;
        for (size_t t = 0; t + 1 < co.size(); ++t) {
            const uint32_t ca = co[t], cn = co[t + 1] - co[t], ga = go[t], gn = go[t + 1] - go[t];
            offset_mismatch += ca != ga || cn != gn;
            const float* cv = cpu_map.vertices[l].data() + size_t(F) * ca;
            const float* gv = gpu.gpu_map.vertices[l].data() + size_t(F) * ga;
            const float* tv = gpu_twin.vertices[l].data() + size_t(F) * to[t];
            if (cn == gn)
                for (uint32_t i = 0; i < F * cn; ++i) vertex_mismatch += bits(cv[i]) != bits(gv[i]);
            not_monotone += !penumbra::dsmMonotone(gv, gn, setup.channels);
            worst_cpu = std::max(worst_cpu, penumbra::dsmFunctionDistance(cv, cn, gv, gn, setup.channels));
            worst_twin = std::max(worst_twin, penumbra::dsmFunctionDistance(tv, to[t + 1] - to[t], gv, gn, setup.channels));
        }
        const double bound = sameFragmentsBound(setup, l);
        MESSAGE("level ", l, ": worst distance to the twin of the GPU's fragments ", worst_twin, ", to the CPU twin ",
                worst_cpu, " (bound ", bound, ")");
        CHECK(not_monotone == 0);
        CHECK(worst_twin <= bound);
        PENUMBRA_CHECK_BITWISE("deep shadow map: every level within 2 eps + 1e-3 of buildDsmMapCpu (same fragments)",
                               worst_cpu <= 2.0 * setup.tolerance + 1e-3);
        PENUMBRA_CHECK_BITWISE("deep shadow map: every level's offsets == buildDsmMapCpu", offset_mismatch == 0);
        PENUMBRA_CHECK_BITWISE("deep shadow map: every level's vertices == buildDsmMapCpu", vertex_mismatch == 0);
    }
}

}  // namespace

TEST_CASE("GPU deep shadow map == CPU twin: hairball, grey opacity, box filter, full mip chain") {
    penumbra::test::context();
    const Casters c = objects(penumbra::scene::hairball(1500, 3, false));
    const auto setup = setupOf(32, 16, 0);
    DsmOpacity op;
    op.mesh = glm::vec3(0.5f);
    compareRun(setup, lightFor(c), op, c);
}

TEST_CASE("GPU deep shadow map == CPU twin: the built-in hairball at 128^2, S = 64, one mip level") {
    // Long, diverging compressor runs per SIMD batch of texels: `continue` in both of the compressor's
    // candidate loops once made texels differ here on llvmpipe (Mesa 22.3); no smaller case caught it.
    penumbra::test::context();
    const Casters c = objects(penumbra::scene::builtin("hairball"));
    const auto setup = setupOf(128, 64, 2);
    DsmOpacity op;
    op.mesh = glm::vec3(0.5f);
    compareRun(setup, lightFor(c), op, c);
}

TEST_CASE("GPU deep shadow map == CPU twin: grass, colour per triangle, Gaussian radius 1, S = 9") {
    penumbra::test::context();
    const Casters c = objects(penumbra::scene::grass(150, 2, false));
    DsmOptions o;
    o.resolution = 32;
    o.samples = 9;
    o.channels = 3;
    o.filter = penumbra::DsmFilter::Gaussian;
    o.filter_radius = 1.0f;
    o.levels = 3;
    o.tolerance = 1.0f / 32.0f;
    const auto setup = penumbra::deepShadowMapSetup(o);
    DsmOpacity op;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (size_t t = 0; t < c.indices.size() / 3; ++t) op.per_triangle.emplace_back(u(rng), u(rng), u(rng));
    compareRun(setup, lightFor(c), op, c);
}

TEST_CASE("GPU deep shadow map == CPU twin: per-vertex opacity, S = 1, odd resolution, one level") {
    penumbra::test::context();
    const Casters c = objects(penumbra::scene::hairball(600, 5, false));
    DsmOptions o;
    o.resolution = 37;
    o.samples = 1;
    o.tolerance = 0.01f;
    const auto setup = penumbra::deepShadowMapSetup(o);
    DsmOpacity op;
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (size_t v = 0; v < c.positions.size(); ++v) {
        const float a = u(rng);
        op.per_vertex.emplace_back(a, a, a);
    }
    compareRun(setup, lightFor(c), op, c);
}

TEST_CASE("GPU deep shadow map == CPU twin: hairball inside a participating medium (box over half of it), mips") {
    penumbra::test::context();
    const Casters c = objects(penumbra::scene::hairball(1200, 6, false));
    penumbra::scene::Bounds b;
    for (const auto& p : c.positions) b.extend(p);
    const auto setup = setupOf(32, 4, 0);
    DsmOpacity op;
    op.mesh = glm::vec3(0.3f);
    penumbra::DsmMedium medium;
    medium.lo = b.min - 0.1f * b.size();
    medium.hi = b.center() + glm::vec3(0.0f, 0.2f, 0.0f) * b.size();
    medium.sigma_t = 2.0f / glm::length(b.size());
    medium.samples = 6;
    compareRun(setup, lightFor(c), op, c, medium);
}

/// Texture coordinates for the hook tests: world x, y scaled so that the casters span a few
/// repeats of the texture (negative and beyond 1 included), z kept.
std::vector<glm::vec3> hookCoordinates(const Casters& c, float repeats) {
    penumbra::scene::Bounds b;
    for (const auto& p : c.positions) b.extend(p);
    std::vector<glm::vec3> uv;
    for (const auto& p : c.positions)
        uv.emplace_back((p.x - b.center().x) / b.size().x * repeats, (p.y - b.center().y) / b.size().y * repeats, p.z);
    return uv;
}

TEST_CASE("GPU deep shadow map == CPU twin: opacity from the default hook (RGB32F texture, repeat, clamping), colour") {
    penumbra::test::context();
    const Casters c = objects(penumbra::scene::hairball(1200, 4, false));
    const auto setup = setupOf(64, 9, 0, 3, 1.0f / 32.0f);
    // 8 x 4 random texels; a few outside [0, 1] and one NaN exercise the clamp (NaN -> 0).
    penumbra::DsmOpacityTexture texture;
    texture.width = 8;
    texture.height = 4;
    std::mt19937 rng(2000);
    std::uniform_real_distribution<float> u(-0.25f, 1.25f);
    for (uint32_t i = 0; i < 32; ++i) texture.texels.emplace_back(u(rng), u(rng), u(rng));
    texture.texels[5].y = std::numeric_limits<float>::quiet_NaN();
    penumbra::gl::Texture gl_texture(GL_TEXTURE_2D);
    glTextureStorage2D(gl_texture.id(), 1, GL_RGB32F, 8, 4);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage2D(gl_texture.id(), 0, 0, 0, 8, 4, GL_RGB, GL_FLOAT, texture.texels.data());
    DsmOpacity op;
    op.mesh = glm::vec3(1.0f);
    op.hook_attribute = hookCoordinates(c, 3.0f);
    op.hook = [&texture](uint32_t, const glm::vec3& a) { return penumbra::dsmOpacityTexel(texture, a); };
    HookGpu hook;
    hook.texture = gl_texture.id();
    compareRun(setup, lightFor(c), op, c, {}, hook);
}

TEST_CASE("GPU deep shadow map == CPU twin: a replaced opacity hook (the engine's own opacity_hook.glsl)") {
    penumbra::test::context();
    const Casters c = objects(penumbra::scene::grass(600, 3, false));
    const auto setup = setupOf(64, 4, 2, 3, 1.0f / 16.0f);
    // A procedural material: by triangle (values -0.25 .. 1.25: clamped) and a stripe of the
    // interpolated attribute. Every operation is exact or a single rounding in both languages.
    penumbra::ShaderLibrary library = penumbra::ShaderLibrary::embedded();
    library.add("penumbra/deep_shadow_map/opacity_hook.glsl", R"(
vec3 penumbraDsmOpacityHook(uint triangle, vec3 coordinates) {
    float stripe = fract(coordinates.x) < 0.5 ? 0.75 : 0.25;
    return vec3(float(triangle % 7u) * 0.25 - 0.25, stripe, 0.5);
}
)");
    DsmOpacity op;
    op.hook_attribute = hookCoordinates(c, 5.0f);
    op.hook = [](uint32_t triangle, const glm::vec3& a) {
        const float stripe = a.x - std::floor(a.x) < 0.5f ? 0.75f : 0.25f;
        return glm::vec3(static_cast<float>(triangle % 7u) * 0.25f - 0.25f, stripe, 0.5f);
    };
    HookGpu hook;
    hook.library = &library;
    compareRun(setup, lightFor(c), op, c, {}, hook);
}

TEST_CASE("GPU deep shadow map lookups == dsmLookup (bilinear, trilinear, border)") {
    penumbra::test::context();
    const Casters c = objects(penumbra::scene::hairball(1000, 9, false));
    const auto setup = setupOf(16, 16, 0);
    const DsmLight light = lightFor(c);
    DsmOpacity op;
    op.mesh = glm::vec3(0.6f);
    penumbra::gl::DeepShadowMapBuilder builder(setup);
    penumbra::gl::Buffer positions = penumbra::gl::Buffer::fromVector(c.positions);
    penumbra::gl::Buffer indices = penumbra::gl::Buffer::fromVector(c.indices);
    penumbra::gl::DsmCasterBuffers casters;
    casters.positions = {positions.id(), 0, positions.size()};
    casters.indices = {indices.id(), 0, indices.size()};
    casters.index_count = static_cast<uint32_t>(c.indices.size());
    builder.build(light, op, casters);
    const DsmMapCpu map = builder.readMap();
    // Queries: depths spread over the casters' range, (u, v) over the map and past its border.
    float zmin = 1e30f, zmax = -1e30f;
    for (const auto& p : c.positions) {
        const float d = penumbra::dsmCoord(builder.params(), p).depth;
        zmin = std::min(zmin, d), zmax = std::max(zmax, d);
    }
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> uv(-0.1f, 1.1f), z(zmin, zmax), lod(-1.0f, 6.0f);
    std::vector<glm::vec4> queries(4096);
    for (auto& q : queries) q = glm::vec4(uv(rng), uv(rng), z(rng), lod(rng));
    queries[0] = glm::vec4(0.5f, 0.5f, zmax, 0.0f);
    penumbra::gl::Buffer qb = penumbra::gl::Buffer::fromVector(queries);
    penumbra::gl::Buffer rb(queries.size() * 16);
    builder.lookup({qb.id(), 0, qb.size()}, {rb.id(), 0, rb.size()}, static_cast<uint32_t>(queries.size()));
    std::vector<glm::vec4> results(queries.size());
    glGetNamedBufferSubData(rb.id(), 0, static_cast<GLsizeiptr>(rb.size()), results.data());
    uint64_t mismatch = 0;
    double worst = 0.0;
    for (size_t i = 0; i < queries.size(); ++i) {
        const auto& q = queries[i];
        const float cpu = penumbra::dsmLookup(map, q.x, q.y, q.z, q.w);
        mismatch += bits(cpu) != bits(results[i].x);
        worst = std::max(worst, std::fabs(double(cpu) - results[i].x));
    }
    MESSAGE("lookups: ", mismatch, " of ", queries.size(), " differ in bits, worst ", worst);
    CHECK(worst <= 1e-4);
    PENUMBRA_CHECK_BITWISE("deep shadow map: lookup.glsl == dsmLookup", mismatch == 0);
}

TEST_CASE("GPU deep shadow map: a fragment capacity too small is counted, never written past") {
    penumbra::test::context();
    const Casters c = objects(penumbra::scene::hairball(800, 4, false));
    DsmOptions o;
    o.resolution = 16;
    o.samples = 4;
    const auto setup = penumbra::deepShadowMapSetup(o);
    penumbra::gl::DsmCapacity capacity;
    capacity.fragments = 64;
    capacity.vertices = 64;
    DsmOpacity op;
    op.mesh = glm::vec3(0.5f);
    const Run r = runGpu(setup, lightFor(c), op, c, capacity);
    CHECK(r.status.fragments > 64);
    CHECK(r.status.fragment_overflow == r.status.fragments - 64);
    CHECK(r.status.vertex_overflow > 0);
    CHECK_THROWS_WITH_AS(penumbra::gl::DeepShadowMapBuilder(setup, {0, 16}), doctest::Contains("fragment capacity 0"),
                         penumbra::Error);
}
