// Alias-free hard shadows (sintorn2008 §3): the blocker test against the oracle on adversarial
// pairs, the GPU pipeline against its CPU twin (bit for bit) and against the exact oracle (0
// mismatches outside reported ties) on every built-in scene and spot.obj with several lights,
// the skips proven bit-identical, multi-pass list blocks, and bad input.
#include <penumbra/gl/headless.hpp>
#include <penumbra/pipelines/alias_free_hard.hpp>
#include <penumbra/reference/visibility.hpp>
#include <penumbra/scene/gl_scene.hpp>
#include <penumbra/scene/obj.hpp>

#include <doctest/doctest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <random>

namespace {

penumbra::gl::HeadlessContext& context() {
    static penumbra::gl::HeadlessContext ctx;
    return ctx;
}

uint32_t testSeed() {
    if (const char* env = std::getenv("PENUMBRA_SEED")) return static_cast<uint32_t>(std::strtoul(env, nullptr, 10));
    return std::random_device{}();
}

// Everything one pipeline run on a scene needs, with CPU copies for the twin and the oracle.
struct Fixture {
    penumbra::scene::Scene scene;
    std::unique_ptr<penumbra::scene::GpuScene> gpu;
    std::unique_ptr<penumbra::scene::GBuffer> gbuffer;
    std::vector<glm::vec4> positions, normals;
    std::vector<uint8_t> closed_per_triangle;
    uint32_t width = 0, height = 0;

    Fixture(penumbra::scene::Scene s, uint32_t w, uint32_t h) : scene(std::move(s)), width(w), height(h) {
        gpu = std::make_unique<penumbra::scene::GpuScene>(scene);
        gbuffer = std::make_unique<penumbra::scene::GBuffer>(w, h);
        gbuffer->render(*gpu, scene.camera.projection(float(w) / float(h)) * scene.camera.view());
        positions = gbuffer->positionBuffer().download<glm::vec4>();
        normals = gbuffer->faceBuffer().download<glm::vec4>();
        for (const auto& r : gpu->ranges()) closed_per_triangle.insert(closed_per_triangle.end(), r.index_count / 3, r.closed ? 1 : 0);
    }

    penumbra::SampleBufferInput input() const {
        return {gbuffer->positionBuffer().id(), gbuffer->faceBuffer().id()};
    }
    uint32_t samples() const { return width * height; }

    penumbra::AliasFreeHardShadows::DrawCasters drawer() const {
        return [this](penumbra::CasterClass cls) {
            for (const auto& r : gpu->ranges()) {
                if (r.closed == (cls == penumbra::CasterClass::Closed)) gpu->draw(r);
            }
        };
    }
    penumbra::AfhCasters casters() const { return {&gpu->positions(), &gpu->indices(), &closed_per_triangle}; }
};

penumbra::SampleListsLight pointLight(const Fixture& f, const glm::vec3& position) {
    const auto [lo, hi] = penumbra::viewSampleBounds(f.positions.data(), f.positions.size());
    penumbra::SampleListsLight light;
    light.light = glm::vec4(position, 1.0f);
    light.view_projection = penumbra::lightViewProjectionForBounds(light.light, lo, hi);
    return light;
}

struct Comparison {
    size_t tested = 0, shadowed = 0, mismatched = 0, ties = 0, back_facing = 0, untested = 0;
};

// GPU states vs the exact oracle with the same light point and coplanar rule, on every listed sample.
Comparison compareWithOracle(const Fixture& f, const penumbra::SampleListsLight& light,
                             const std::vector<uint32_t>& states, double coplanar_epsilon, float reach) {
    penumbra::reference::VisibilityOracle oracle(f.gpu->positions(), f.gpu->indices());
    penumbra::reference::VisibilityOptions options;
    options.coplanar_epsilon = coplanar_epsilon;
    Comparison c;
    std::vector<glm::dvec3> receivers;
    std::vector<uint32_t> ids;
    for (uint32_t id = 0; id < states.size(); ++id) {
        if (states[id] == PENUMBRA_AFH_BACK_FACING) ++c.back_facing;
        if (states[id] == PENUMBRA_AFH_UNTESTED) ++c.untested;
        if (states[id] != PENUMBRA_AFH_LIT && states[id] != PENUMBRA_AFH_SHADOWED) continue;
        receivers.emplace_back(glm::vec3(f.positions[id]));
        ids.push_back(id);
    }
    c.tested = receivers.size();
    if (light.light.w != 0.0f) {
        const auto result = oracle.evaluate(receivers, {glm::dvec3(glm::vec3(light.light))}, options);
        for (size_t r = 0; r < receivers.size(); ++r) {
            const bool gpu = states[ids[r]] == PENUMBRA_AFH_SHADOWED;
            c.shadowed += gpu;
            if (result.isTie(r, 0)) {
                ++c.ties;
                continue;
            }
            if (gpu != result.isBlocked(r, 0)) {
                ++c.mismatched;
                if (c.mismatched <= 5) {
                    // Name the triangles that decide it, for the report.
                    const glm::dvec3 p = receivers[r], l(glm::vec3(light.light));
                    std::string blockers;
                    const auto& P = f.gpu->positions();
                    const auto& I = f.gpu->indices();
                    for (size_t t = 0; t < I.size() / 3; ++t) {
                        const glm::dvec3 a(P[I[3 * t]]), b(P[I[3 * t + 1]]), cc(P[I[3 * t + 2]]);
                        if (penumbra::afhBlocks<double>(a, b, cc, p, l, coplanar_epsilon, 0.0)) {
                            blockers += " " + std::to_string(t) + (f.closed_per_triangle[t] ? "c" : "o") +
                                        (glm::dot(glm::cross(b - a, cc - a), l - a) < 0 ? "B" : "F");
                        }
                    }
                    const auto hit = oracle.closestHit(p, l - p, 0.0, 1.0);
                    uint32_t own = 0;
                    std::memcpy(&own, &f.normals[ids[r]].w, 4);
                    {
                        const auto& P = f.gpu->positions();
                        const auto& I = f.gpu->indices();
                        for (uint32_t t : {own, hit.triangle}) {
                            const glm::dvec3 a(P[I[3 * t]]), b(P[I[3 * t + 1]]), cc(P[I[3 * t + 2]]);
                            const glm::dvec3 n = glm::normalize(glm::cross(b - a, cc - a));
                            MESSAGE("  tri ", t, " idx ", I[3*t], " ", I[3*t+1], " ", I[3*t+2], " n.(l-p) ", glm::dot(n, l - p),
                                    " dist(p) ", glm::dot(n, p - a), " gbuf normal.n ", glm::dot(n, glm::dvec3(glm::vec3(f.normals[ids[r]]))));
                        }
                    }
                    MESSAGE("  first crossing t = ", hit.t, " triangle ", hit.triangle, "; sample's own triangle ", own,
                            " distance to crossing ", hit.t * glm::length(l - p));
                    MESSAGE("mismatch: sample ", ids[r], " (", p.x, ", ", p.y, ", ", p.z, ") gpu ", gpu, " oracle ",
                            result.isBlocked(r, 0), "; afhBlocks triangles:", blockers);
                }
            }
        }
    } else {
        const glm::dvec3 dir(glm::vec3(light.light));
        for (size_t r = 0; r < receivers.size(); ++r) {
            const bool gpu = states[ids[r]] == PENUMBRA_AFH_SHADOWED;
            c.shadowed += gpu;
            bool tie = false;
            const bool blocked = oracle.segmentBlocked(receivers[r], receivers[r] + dir * double(reach), options, &tie);
            if (tie) {
                ++c.ties;
                continue;
            }
            c.mismatched += gpu != blocked;
        }
    }
    return c;
}

std::vector<glm::vec3> lightPositions(const penumbra::scene::Scene& scene) {
    const glm::vec3 l = scene.light.position;
    const glm::vec3 c = scene.bounds().min * 0.5f + scene.bounds().max * 0.5f;
    const glm::vec3 d = l - c;
    // The scene's own light, and the same light swung 120 and 240 degrees around the vertical,
    // the last one lower (longer shadows).
    const float cs = std::cos(2.0944f), sn = std::sin(2.0944f);
    return {l, c + glm::vec3(cs * d.x - sn * d.z, d.y, sn * d.x + cs * d.z),
            c + glm::vec3(cs * d.x + sn * d.z, 0.8f * d.y, -sn * d.x + cs * d.z)};
}

}  // namespace

TEST_CASE("blocker test == oracle on random and adversarial pairs (outside ties)") {
    const uint32_t seed = testSeed();
    MESSAGE("seed ", seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    size_t pairs = 0, ties = 0, mismatched = 0, blocked = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const float offset = trial % 4 == 3 ? 1e5f : 0.0f;  // far from the origin
        std::vector<glm::vec3> positions = {glm::vec3(u(rng), u(rng), u(rng)) + offset, glm::vec3(u(rng), u(rng), u(rng)) + offset,
                                            glm::vec3(u(rng), u(rng), u(rng)) + offset};
        if (trial % 5 == 1) positions[2] = positions[0] + (positions[1] - positions[0]) * 0.5f + glm::vec3(1e-6f);  // sliver
        const std::vector<uint32_t> indices = {0, 1, 2};
        penumbra::reference::VisibilityOracle oracle(positions, indices);
        penumbra::reference::VisibilityOptions options;
        options.coplanar_epsilon = 1e-6;
        const glm::vec3 light = glm::vec3(u(rng), 2.0f + u(rng), u(rng)) + offset;
        for (int k = 0; k < 100; ++k) {
            glm::vec3 p = glm::vec3(u(rng), -2.0f + u(rng), u(rng)) * 2.0f + offset;
            const int kind = k % 4;
            if (kind == 1) {  // on the triangle's plane, inside or near it
                const float a = std::abs(u(rng)), b = std::abs(u(rng)) * (1 - a);
                p = positions[0] + a * (positions[1] - positions[0]) + b * (positions[2] - positions[0]);
            } else if (kind == 2) {  // shadow boundary: the line from the light through an edge point
                const float t = std::abs(u(rng));
                const glm::vec3 e = positions[0] + t * (positions[1] - positions[0]);
                p = light + (e - light) * (1.5f + std::abs(u(rng)));
            }
            bool tie = false;
            const bool expected = oracle.segmentBlocked(glm::dvec3(p), glm::dvec3(light), options, &tie);
            const bool got = penumbra::afhBlocks<double>(glm::dvec3(positions[0]), glm::dvec3(positions[1]), glm::dvec3(positions[2]),
                                                        glm::dvec3(p), glm::dvec3(light), 1e-6, 0.0);
            ++pairs;
            if (tie) {
                ++ties;
                continue;
            }
            blocked += expected;
            if (got != expected) {
                ++mismatched;
                MESSAGE("mismatch at trial ", trial, " k ", k, ": oracle ", expected, " test ", got);
            }
        }
    }
    MESSAGE(pairs, " pairs, ", blocked, " blocked, ", ties, " ties, ", mismatched, " mismatched");
    CHECK(blocked > pairs / 20);
    CHECK(mismatched == 0);
}

TEST_CASE("GPU pipeline == CPU twin, both raster variants and precisions; skips are bit-identical") {
    context();
    Fixture f(penumbra::scene::builtin("torus_knot"), 96, 72);
    const auto light = pointLight(f, f.scene.light.position);
    std::vector<uint32_t> reference_states;
    for (auto variant : {penumbra::ConservativeVariant::Fixed6, penumbra::ConservativeVariant::Exact}) {
        for (auto precision : {penumbra::AfhPrecision::Exact, penumbra::AfhPrecision::Fast}) {
            for (int skips = 0; skips < 2; ++skips) {
                CAPTURE(int(variant));
                CAPTURE(int(precision));
                CAPTURE(skips);
                penumbra::AliasFreeHardOptions o;
                o.grid_width = 96;
                o.grid_height = 72;
                o.variant = variant;
                o.precision = precision;
                o.skip_shadowed = skips == 1;
                o.clip_to_box = skips == 1;
                penumbra::AliasFreeHardShadows pipeline(o);
                const auto& frame = pipeline.run(f.input(), f.samples(), light, f.drawer());
                const auto states = pipeline.stateBuffer().download<uint32_t>(0, f.samples());
                penumbra::SampleListsLight fitted = light;
                fitted.view_projection = frame.light_view_projection;
                const auto cpu = penumbra::aliasFreeHardCpu(o, fitted, f.positions.data(), f.normals.data(), f.samples(), f.casters());
                size_t differ = 0, shadowed = 0;
                for (size_t i = 0; i < states.size(); ++i) {
                    differ += states[i] != cpu[i];
                    shadowed += states[i] == PENUMBRA_AFH_SHADOWED;
                }
                CHECK(differ == 0);
                CHECK(shadowed > 100);
                if (precision == penumbra::AfhPrecision::Exact) {
                    if (reference_states.empty()) reference_states = states;
                    CHECK(states == reference_states);  // variant and skips change nothing
                }
            }
        }
    }
    // The exact mode's float filter (default) against fp64-only blocker tests: same states.
    for (auto variant : {penumbra::ConservativeVariant::Fixed6, penumbra::ConservativeVariant::Exact}) {
        penumbra::AliasFreeHardOptions o;
        o.grid_width = 96;
        o.grid_height = 72;
        o.variant = variant;
        o.fp64_only = true;
        penumbra::AliasFreeHardShadows pipeline(o);
        pipeline.run(f.input(), f.samples(), light, f.drawer());
        CHECK(pipeline.stateBuffer().download<uint32_t>(0, f.samples()) == reference_states);
    }
}

TEST_CASE("0 mismatches against the oracle on every scene with three point lights, 256x256") {
    context();
    std::vector<std::pair<std::string, penumbra::scene::Scene>> scenes;
    for (const auto& name : penumbra::scene::builtinNames()) scenes.emplace_back(name, penumbra::scene::builtin(name));
    const std::string spot = std::string(PENUMBRA_SHARED_SCENES_DIR) + "/spot.obj";
    if (std::filesystem::exists(spot)) {
        scenes.emplace_back("spot.obj", penumbra::scene::loadObj(spot));
    } else {
        MESSAGE("skipping spot.obj: ", spot, " is absent");
    }
    // PENUMBRA_AFH_SIZE overrides the view size (e.g. 512 for the larger check).
    // PENUMBRA_AFH_SIZE=W or WxH overrides the 256x256 view (e.g. 512x384, the demo's size).
    const char* size_env = std::getenv("PENUMBRA_AFH_SIZE");
    uint32_t size = 256, height = 256;
    if (size_env) {
        char* end = nullptr;
        size = height = static_cast<uint32_t>(std::strtoul(size_env, &end, 10));
        if (end && *end == 'x') height = static_cast<uint32_t>(std::strtoul(end + 1, nullptr, 10));
    }
    for (auto& [name, scene] : scenes) {
        Fixture f(scene, size, height);
        for (const auto& position : lightPositions(f.scene)) {
            CAPTURE(name);
            const auto light = pointLight(f, position);
            penumbra::AliasFreeHardOptions o;
            o.grid_width = size;
            o.grid_height = height;
            penumbra::AliasFreeHardShadows pipeline(o);
            pipeline.run(f.input(), f.samples(), light, f.drawer());
            const auto states = pipeline.stateBuffer().download<uint32_t>(0, f.samples());
            const Comparison c = compareWithOracle(f, light, states, o.coplanar_epsilon, 0.0f);
            MESSAGE(name, " light (", position.x, ", ", position.y, ", ", position.z, "): ", c.tested, " samples, ",
                    c.shadowed, " shadowed, mismatched ", c.mismatched, ", ties ", c.ties, " (back-facing ",
                    c.back_facing, ", untested ", c.untested, ")");
            CHECK(c.tested > size * height / 8);
            CHECK(c.untested == 0);
            CHECK(c.mismatched == 0);
            CHECK(double(c.ties) < 1e-4 * double(c.tested));
        }
    }
}

TEST_CASE("closed casters with every face cast equal the oracle too, at the demo's 512x384") {
    context();
    Fixture f(penumbra::scene::builtin("torus_knot"), 512, 384);
    const auto light = pointLight(f, f.scene.light.position);
    for (bool back_faces_only : {true, false}) {
        penumbra::AliasFreeHardOptions o;
        o.grid_width = 512;
        o.grid_height = 384;
        o.back_faces_only = back_faces_only;
        o.count_work = true;
        penumbra::AliasFreeHardShadows pipeline(o);
        const auto& frame = pipeline.run(f.input(), f.samples(), light, f.drawer());
        const auto states = pipeline.stateBuffer().download<uint32_t>(0, f.samples());
        const Comparison c = compareWithOracle(f, light, states, o.coplanar_epsilon, 0.0f);
        MESSAGE("torus_knot 512x384, back_faces_only=", back_faces_only, ": ", c.tested, " samples, mismatched ",
                c.mismatched, ", ties ", c.ties, ", triangles emitted ", frame.triangles_emitted);
        // §3.3 (back faces only) misses samples exactly in concave creases lit at a grazing angle:
        // reported, bounded; casting every face of closed meshes removes them.
        if (back_faces_only) CHECK(double(c.mismatched) <= 1e-4 * double(c.tested));
        else CHECK(c.mismatched == 0);
    }
}

TEST_CASE("directional light: 0 mismatches against the oracle") {
    context();
    Fixture f(penumbra::scene::builtin("columns"), 128, 128);
    penumbra::SampleListsLight light;
    light.light = glm::vec4(glm::normalize(glm::vec3(-0.4f, 1.0f, 0.3f)), 0.0f);
    const auto b = f.scene.bounds();
    light.view_projection = penumbra::lightViewProjectionForBounds(light.light, b.min, b.max);
    penumbra::AliasFreeHardOptions o;
    o.grid_width = 128;
    o.grid_height = 128;
    o.directional_reach = 4.0f * glm::length(b.max - b.min);
    penumbra::AliasFreeHardShadows pipeline(o);
    pipeline.run(f.input(), f.samples(), light, f.drawer());
    const auto states = pipeline.stateBuffer().download<uint32_t>(0, f.samples());
    const Comparison c = compareWithOracle(f, light, states, o.coplanar_epsilon, o.directional_reach);
    MESSAGE("directional: ", c.tested, " samples, ", c.shadowed, " shadowed, mismatched ", c.mismatched, ", ties ", c.ties);
    CHECK(c.shadowed > 100);
    CHECK(c.mismatched == 0);
}

TEST_CASE("long lists are walked in blocks over several passes with identical results") {
    context();
    Fixture f(penumbra::scene::builtin("hairball"), 96, 96);
    const auto light = pointLight(f, f.scene.light.position);
    std::vector<uint32_t> one_pass;
    for (uint32_t block : {2048u, 3u, 1u}) {
        penumbra::AliasFreeHardOptions o;
        o.grid_width = 24;  // a coarse grid: long lists
        o.grid_height = 24;
        o.list_block = block;
        penumbra::AliasFreeHardShadows pipeline(o);
        const auto& frame = pipeline.run(f.input(), f.samples(), light, f.drawer());
        CAPTURE(block);
        CHECK(frame.passes == (frame.statistics.max_list_length + block - 1) / block);
        const auto states = pipeline.stateBuffer().download<uint32_t>(0, f.samples());
        if (one_pass.empty()) {
            one_pass = states;
            CHECK(frame.passes == 1);
        } else {
            CHECK(frame.passes > 1);
            CHECK(states == one_pass);
        }
    }
}

TEST_CASE("exact mode's float filter: share of light-pass blocker tests that fall back to double") {
    context();
    for (const std::string& name : penumbra::scene::builtinNames()) {
        Fixture f(penumbra::scene::builtin(name), 256, 256);
        const auto light = pointLight(f, f.scene.light.position);
        penumbra::AliasFreeHardOptions o;
        o.grid_width = 256;
        o.grid_height = 256;
        o.count_work = true;
        penumbra::AliasFreeHardShadows pipeline(o);
        const auto& frame = pipeline.run(f.input(), f.samples(), light, f.drawer());
        MESSAGE(name, ": tests ", frame.tests, ", fallbacks ", frame.fallbacks, " (",
                100.0 * double(frame.fallbacks) / double(std::max<uint64_t>(frame.tests, 1)), " %)");
        CHECK(frame.fallbacks < frame.tests);
    }
}

TEST_CASE("work counters and zero samples") {
    context();
    Fixture f(penumbra::scene::builtin("torus_knot"), 64, 64);
    const auto light = pointLight(f, f.scene.light.position);
    penumbra::AliasFreeHardOptions o;
    o.grid_width = 64;
    o.grid_height = 64;
    o.count_work = true;
    penumbra::AliasFreeHardShadows pipeline(o);
    const auto& frame = pipeline.run(f.input(), f.samples(), light, f.drawer());
    MESSAGE("fragments ", frame.fragments, ", tests ", frame.tests, ", triangles emitted ", frame.triangles_emitted,
            " of ", f.gpu->triangleCount());
    CHECK(frame.fragments > 0);
    CHECK(frame.tests > 0);
    CHECK(frame.triangles_emitted > 0);
    CHECK(frame.triangles_emitted < f.gpu->triangleCount());  // closed torus knot: front faces culled (§3.3)
    const auto& empty = pipeline.run(f.input(), 0, light, f.drawer());
    CHECK(empty.passes == 0);
    // The view-sample box skips "no sample" entries (w == 0) and counts the others.
    const std::vector<glm::vec4> some = {{1, 2, 3, 1}, {9, 9, 9, 0}, {-1, 5, 0, 1}};
    size_t counted = 0;
    const auto [lo, hi] = penumbra::viewSampleBounds(some.data(), some.size(), &counted);
    CHECK(counted == 2);
    CHECK(lo == glm::vec3(-1, 2, 0));
    CHECK(hi == glm::vec3(1, 5, 3));
    CHECK(penumbra::viewSampleBounds(some.data(), 0, &counted).first == glm::vec3(0));
    CHECK(counted == 0);
}

TEST_CASE("bad input is a clear error") {
    context();
    penumbra::AliasFreeHardOptions o;
    CHECK_THROWS_WITH_AS(penumbra::AliasFreeHardShadows{o}, doctest::Contains("grid"), penumbra::Error);
    o.grid_width = o.grid_height = 16;
    o.coplanar_epsilon = -1;
    CHECK_THROWS_AS(penumbra::AliasFreeHardShadows{o}, penumbra::Error);
    o.coplanar_epsilon = 1e-6;
    o.list_block = 0;
    CHECK_THROWS_AS(penumbra::AliasFreeHardShadows{o}, penumbra::Error);
    o.list_block = 64;
    CHECK_THROWS_WITH_AS(penumbra::lightViewProjectionForBounds(glm::vec4(0.1f, 0, 0, 1), glm::vec3(-1), glm::vec3(1)),
                         doctest::Contains("inside it"), penumbra::Error);
    CHECK_THROWS_AS(penumbra::lightViewProjectionForBounds(glm::vec4(NAN, 0, 0, 1), glm::vec3(-1), glm::vec3(1)),
                    penumbra::Error);
    penumbra::AliasFreeHardShadows pipeline(o);
    penumbra::SampleListsLight directional;
    directional.light = glm::vec4(0, 1, 0, 0);
    penumbra::gl::Buffer positions(16), normals(16);
    const penumbra::SampleBufferInput input{positions.id(), normals.id()};
    auto nothing = [](penumbra::CasterClass) {};
    CHECK_THROWS_WITH_AS(pipeline.run(input, 1, directional, nothing), doctest::Contains("directional_reach"),
                         penumbra::Error);
    directional.light = glm::vec4(0, 2, 0, 0);
    CHECK_THROWS_WITH_AS(pipeline.run(input, 1, directional, nothing), doctest::Contains("unit"), penumbra::Error);
    penumbra::SampleListsLight point;
    point.light = glm::vec4(0, 2, 0, 1);
    CHECK_THROWS_AS(pipeline.run(input, 5, point, nothing), penumbra::Error);  // buffers too small
    CHECK_THROWS_AS(pipeline.run(input, 1, point, {}), penumbra::Error);
}
