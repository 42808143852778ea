// gl/shadow_edge_stencil.hpp (galoppo2010) on the GPU against its CPU twin: the sub-samples
// (aaFootprintsCpu), the provable stencil's words (provableEdgeStencilCpu), the extended sample
// buffer (aaSampleBuffer) and, through the alias-free hard pipeline on the GPU, the resolve
// (aaResolve) — bit for bit on a correctly rounded driver (PENUMBRA_CHECK_BITWISE: llvmpipe; on
// other drivers only the driver-independent checks run: every unflagged pixel's points agree,
// edge == full). Bad input: the Status codes.
#include "penumbra/gl/gl.hpp"
#include "penumbra/gl/pipelines/alias_free_hard.hpp"
#include "penumbra/gl/shadow_edge_stencil.hpp"
#include "penumbra/scene/gl_scene.hpp"
#include "penumbra/scene/scene.hpp"

#include "support/gl_test_support.hpp"

#include "penumbra/reference/visibility.hpp"

#include <doctest/doctest.h>

#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace {

using glm::vec3;
using glm::vec4;

struct Frame {
    penumbra::scene::Scene scene;
    std::unique_ptr<penumbra::scene::GpuScene> gpu;
    std::unique_ptr<penumbra::scene::GBuffer> gbuffer;
    std::vector<vec4> centres, normals;
    std::vector<uint8_t> closed;
    penumbra::SampleListsView view;
    uint32_t width, height;
    Frame(penumbra::scene::Scene s, uint32_t w, uint32_t h) : scene(std::move(s)), width(w), height(h) {
        gpu = std::make_unique<penumbra::scene::GpuScene>(scene);
        gbuffer = std::make_unique<penumbra::scene::GBuffer>(w, h);
        const glm::mat4 camera = scene.camera.projection(float(w) / float(h)) * scene.camera.view();
        gbuffer->render(*gpu, camera);
        centres = gbuffer->positionBuffer().download<vec4>();
        normals = gbuffer->faceBuffer().download<vec4>();
        closed.assign(gpu->indices().size() / 3, 0);  // the GPU stencil casts every triangle
        view.width = w;
        view.height = h;
        view.inverse_view_projection = glm::inverse(camera);
    }
    penumbra::AfhCasters casters() const { return {&gpu->positions(), &gpu->indices(), &closed}; }
    penumbra::gl::AaCasterBuffers casterBuffers() const {
        penumbra::gl::AaCasterBuffers c;
        c.positions = {gpu->vertexBuffer(), 0, gpu->positions().size() * 24};
        c.indices = {gpu->indexBuffer(), 0, gpu->indices().size() * 4};
        c.index_count = gpu->indexCount();
        c.stride = 24;
        return c;
    }
    penumbra::BufferRange centreRange() const { return {gbuffer->positionBuffer().id(), 0, gbuffer->positionBuffer().size()}; }
    penumbra::BufferRange normalRange() const { return {gbuffer->faceBuffer().id(), 0, gbuffer->faceBuffer().size()}; }
};

size_t countDiffering(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
    size_t n = a.size() == b.size() ? 0 : std::max(a.size(), b.size());
    for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) n += a[i] != b[i];
    return n;
}

void runScene(const std::string& name, penumbra::scene::Scene scene, const vec4& light_vector, uint32_t samples, float reach,
              double coplanar_epsilon = 1e-7, double scene_extent = std::numeric_limits<double>::infinity()) {
    penumbra::test::context();
    Frame f(std::move(scene), 64, 48);
    penumbra::AaPatternOptions pattern;
    pattern.samples = samples;
    const penumbra::AaFootprints cpu_f = penumbra::aaFootprintsCpu(f.view, f.centres.data(), f.normals.data(), pattern);
    penumbra::SampleListsLight light;
    light.light = light_vector;
    const auto [lo, hi] = penumbra::aaFootprintBounds(cpu_f);
    light.view_projection = penumbra::lightViewProjectionForBounds(light.light, lo, hi);
    penumbra::AliasFreeHardOptions o;
    o.grid_width = f.width;
    o.grid_height = f.height;
    o.directional_reach = reach;
    o.max_list_blocks = 64;
    o.coplanar_epsilon = coplanar_epsilon;
    o.scene_extent = scene_extent;

    penumbra::gl::ShadowEdgeStencil stencil(f.width, f.height, o, pattern);
    REQUIRE(stencil.run(f.centreRange(), f.normalRange(), f.view, light, f.casterBuffers()) == penumbra::Status::Ok);
    const std::vector<vec4> gpu_subs = stencil.readSubSamples();
    const std::vector<uint32_t> gpu_words = stencil.readStencil();
    const auto status = stencil.readStatus();
    CHECK(status[PENUMBRA_AA_STATUS_LIST_OVERFLOW] == 0);

    size_t sub_bits = 0;
    for (size_t i = 0; i < gpu_subs.size(); ++i) sub_bits += std::memcmp(&gpu_subs[i], &cpu_f.sub_samples[i], sizeof(vec4)) != 0;
    PENUMBRA_CHECK_BITWISE("sub-samples == aaFootprintsCpu", sub_bits == 0);
    // The twin on the GPU's own sub-samples (so the stencil comparison stands even off llvmpipe).
    penumbra::AaFootprints gpu_f = cpu_f;
    gpu_f.sub_samples = gpu_subs;
    const penumbra::ProvableStencilCpu twin = penumbra::provableEdgeStencilCpu(o, light, gpu_f, f.casters());
    const std::vector<uint32_t> twin_words = twin.words();
    const size_t word_diff = countDiffering(gpu_words, twin_words);
    PENUMBRA_CHECK_BITWISE("stencil words == provableEdgeStencilCpu", word_diff == 0);

    // The hard pipeline on the GPU's edge and full buffers; the resolve on the GPU.
    penumbra::gl::Buffer edge_pos(stencil.sampleBufferBytes()), edge_nrm(stencil.sampleBufferBytes());
    penumbra::gl::Buffer full_pos(stencil.sampleBufferBytes()), full_nrm(stencil.sampleBufferBytes());
    auto whole = [](const penumbra::gl::Buffer& b) { return penumbra::BufferRange{b.id(), 0, b.size()}; };
    REQUIRE(stencil.writeSampleBuffer(penumbra::AaMode::Edge, whole(edge_pos), whole(edge_nrm)) == penumbra::Status::Ok);
    REQUIRE(stencil.writeSampleBuffer(penumbra::AaMode::Full, whole(full_pos), whole(full_nrm)) == penumbra::Status::Ok);
    std::vector<vec4> cpu_pos, cpu_nrm;
    std::vector<uint8_t> gpu_flags(gpu_words.size()), gpu_lit(gpu_words.size());
    for (size_t i = 0; i < gpu_words.size(); ++i) {
        gpu_flags[i] = (gpu_words[i] & PENUMBRA_AA_FLAG) ? 1 : 0;
        gpu_lit[i] = (gpu_words[i] & PENUMBRA_AA_LIT) ? 1 : 0;
    }
    // The provable stencil's edge layout: unflagged pixels are no samples (AaUnflagged::Proven).
    const penumbra::AaUnflagged proven = penumbra::AaUnflagged::Proven;
    penumbra::aaSampleBuffer(gpu_f, gpu_flags.data(), cpu_pos, cpu_nrm, penumbra::kAaAllPixels, proven);
    CHECK(std::memcmp(edge_pos.download<vec4>().data(), cpu_pos.data(), cpu_pos.size() * sizeof(vec4)) == 0);
    CHECK(std::memcmp(edge_nrm.download<vec4>().data(), cpu_nrm.data(), cpu_nrm.size() * sizeof(vec4)) == 0);

    const uint32_t count = uint32_t(cpu_pos.size());
    penumbra::AliasFreeHardShadows pipeline(o);
    pipeline.reserve(count);
    auto draw = [&](penumbra::CasterClass cls) {
        if (cls == penumbra::CasterClass::Open) f.gpu->draw();
    };
    std::vector<std::vector<uint32_t>> states(2);
    std::vector<std::vector<float>> visible(2);
    penumbra::gl::Buffer visible_buffer(4ull * f.width * f.height);
    for (int m = 0; m < 2; ++m) {
        const penumbra::gl::Buffer& pos = m == 0 ? edge_pos : full_pos;
        const penumbra::gl::Buffer& nrm = m == 0 ? edge_nrm : full_nrm;
        REQUIRE(pipeline.run(penumbra::SampleBufferInput{whole(pos), whole(nrm)}, count, light, draw) == penumbra::Status::Ok);
        states[m] = pipeline.stateBuffer().download<uint32_t>(0, count);
        const penumbra::AaMode mode = m == 0 ? penumbra::AaMode::Edge : penumbra::AaMode::Full;
        REQUIRE(stencil.resolve(mode, {pipeline.stateBuffer().id(), 0, 4ull * count}, whole(visible_buffer)) == penumbra::Status::Ok);
        visible[m] = visible_buffer.download<float>();
        const std::vector<float> cpu_visible = penumbra::aaResolve(mode, states[m], f.width * f.height, samples, gpu_flags.data(),
                                                                   penumbra::kAaAllPixels, gpu_lit.data());
        CHECK(visible[m] == cpu_visible);
    }
    // Edge holds every flagged pixel here, and the stencil decided the others: no centre is a
    // sample (w == 0), so the hard pipeline tested only the flagged pixels' sub-samples.
    size_t centres_tested = 0;
    for (size_t i = 0; i < gpu_flags.size(); ++i) centres_tested += states[0][i] != PENUMBRA_AFH_NO_SAMPLE;
    CHECK(centres_tested == 0);
    // The packed edge layout under a budget B of pixels (the engine runs sampleCount(Edge, B)
    // samples): B = the flagged count holds them all (== full), B = half of it leaves the rest
    // single-sampled and counted in the status; GPU == twin either way.
    {
        const uint32_t pixels = f.width * f.height;
        uint32_t flagged_count = 0;
        for (uint8_t flag : gpu_flags) flagged_count += flag;
        for (const uint32_t budget : {flagged_count, flagged_count / 2}) {
            CAPTURE(budget);
            const uint32_t budget_count = stencil.sampleCount(penumbra::AaMode::Edge, budget);
            REQUIRE(budget_count == pixels + budget * samples);
            REQUIRE(stencil.writeSampleBuffer(penumbra::AaMode::Edge, whole(edge_pos), whole(edge_nrm), budget) ==
                    penumbra::Status::Ok);
            std::vector<vec4> budget_pos, budget_nrm;
            penumbra::aaSampleBuffer(gpu_f, gpu_flags.data(), budget_pos, budget_nrm, budget, proven);
            REQUIRE(budget_pos.size() == budget_count);
            CHECK(std::memcmp(edge_pos.download<vec4>(0, budget_count).data(), budget_pos.data(), budget_count * sizeof(vec4)) == 0);
            CHECK(std::memcmp(edge_nrm.download<vec4>(0, budget_count).data(), budget_nrm.data(), budget_count * sizeof(vec4)) == 0);
            REQUIRE(pipeline.run(penumbra::SampleBufferInput{whole(edge_pos), whole(edge_nrm)}, budget_count, light, draw) ==
                    penumbra::Status::Ok);
            const std::vector<uint32_t> budget_states = pipeline.stateBuffer().download<uint32_t>(0, budget_count);
            REQUIRE(stencil.resolve(penumbra::AaMode::Edge, {pipeline.stateBuffer().id(), 0, 4ull * budget_count},
                                    whole(visible_buffer), budget) == penumbra::Status::Ok);
            const std::vector<float> budget_visible = visible_buffer.download<float>();
            CHECK(budget_visible ==
                  penumbra::aaResolve(penumbra::AaMode::Edge, budget_states, pixels, samples, gpu_flags.data(), budget,
                                      gpu_lit.data()));
            CHECK(stencil.readStatus()[PENUMBRA_AA_STATUS_BUDGET_OVERFLOW] ==
                  penumbra::aaBudgetOverflow(gpu_flags.data(), pixels, budget));
            if (budget == flagged_count) CHECK(budget_visible == visible[1]);
            // Too small a range for the budget's layout.
            CHECK(stencil.resolve(penumbra::AaMode::Edge, {pipeline.stateBuffer().id(), 0, 4ull * budget_count - 4},
                                  whole(visible_buffer), budget) == penumbra::Status::RangeTooSmall);
        }
    }

    // Driver-independent: every unflagged pixel's points agree in the full run; edge == full.
    const uint32_t p = f.width * f.height;
    size_t missed = 0, flagged = 0, surface = 0;
    for (uint32_t i = 0; i < p; ++i) {
        if (f.centres[i].w == 0.0f) continue;
        ++surface;
        flagged += gpu_flags[i];
        bool agree = true;
        for (uint32_t k = 0; k < samples; ++k) agree = agree && states[1][p + size_t(i) * samples + k] == states[1][i];
        missed += !agree && !gpu_flags[i];
    }
    MESSAGE(name << ": " << surface << " surface pixels, " << flagged << " flagged, " << status[PENUMBRA_AA_STATUS_PAIRS]
                 << " pairs, " << status[PENUMBRA_AA_STATUS_EXACT] << " exact tests; words differing from the twin: " << word_diff
                 << ", sub-sample bits: " << sub_bits);
    CHECK(missed == 0);
    CHECK(visible[0] == visible[1]);
    CHECK(flagged > 0);

    // galoppo2010's Chebyshev stencil on the GPU: the moment map and the flags against the twins.
    for (const bool inner : {false, true}) {
        penumbra::ChebyshevStencilOptions co;
        co.inner_shadow_proof = inner;
        penumbra::gl::ShadowEdgeStencil chebyshev(f.width, f.height, o, pattern, {}, 1u << 16,
                                                  penumbra::ShaderLibrary::embedded(), penumbra::gl::AaStencilKind::Chebyshev, co);
        REQUIRE(chebyshev.run(f.centreRange(), f.normalRange(), f.view, light, f.casterBuffers()) == penumbra::Status::Ok);
        const penumbra::MomentMapCpu map = penumbra::conservativeMomentMapCpu(o, light, f.casters());
        std::vector<glm::vec2> cpu_moments;
        std::vector<float> cpu_covers;
        for (size_t l = 0; l < map.levels.size(); ++l) {
            cpu_moments.insert(cpu_moments.end(), map.levels[l].begin(), map.levels[l].end());
            cpu_covers.insert(cpu_covers.end(), map.cover[l].begin(), map.cover[l].end());
        }
        const std::vector<glm::vec2> gpu_moments = chebyshev.readMoments();
        const std::vector<float> gpu_covers = chebyshev.readCovers();
        REQUIRE(gpu_moments.size() == cpu_moments.size());
        size_t moment_bits = 0, cover_bits = 0;
        for (size_t t = 0; t < cpu_moments.size(); ++t) {
            moment_bits += std::memcmp(&gpu_moments[t], &cpu_moments[t], sizeof(glm::vec2)) != 0;
            cover_bits += std::memcmp(&gpu_covers[t], &cpu_covers[t], sizeof(float)) != 0;
        }
        const std::vector<uint8_t> cpu_flags = penumbra::chebyshevEdgeStencilCpu(map, light, gpu_f, co);
        const std::vector<uint32_t> gpu_cheb = chebyshev.readStencil();
        size_t flag_diff = 0, cheb_flagged = 0, cheb_missed = 0;
        for (uint32_t i = 0; i < p; ++i) {
            flag_diff += (gpu_cheb[i] == PENUMBRA_AA_FLAG) != (cpu_flags[i] != 0) || (gpu_cheb[i] & ~PENUMBRA_AA_FLAG) != 0;
            if (f.centres[i].w == 0.0f) continue;
            cheb_flagged += cpu_flags[i];
            bool agree = true;
            for (uint32_t k = 0; k < samples; ++k) agree = agree && states[1][p + size_t(i) * samples + k] == states[1][i];
            cheb_missed += !agree && !cpu_flags[i];
        }
        MESSAGE(name << std::string(inner ? ", Chebyshev + inner proof: " : ", Chebyshev: ") << cheb_flagged << " flagged, " << cheb_missed
                     << " edge pixels missed; moments differing " << moment_bits << ", covers " << cover_bits << ", flags " << flag_diff);
        PENUMBRA_CHECK_BITWISE("moment map == conservativeMomentMapCpu", moment_bits + cover_bits == 0);
        PENUMBRA_CHECK_BITWISE("Chebyshev flags == chebyshevEdgeStencilCpu", flag_diff == 0);
    }
}

}  // namespace

TEST_CASE("GPU stencil == CPU twin; edge == full through the GPU hard pipeline") {
    runScene("columns 4x", penumbra::scene::columns(5), vec4(penumbra::scene::columns(5).light.position, 1.0f), 4, 0.0f);
    runScene("grass 8x", penumbra::scene::grass(120), vec4(penumbra::scene::grass(120).light.position, 1.0f), 8, 0.0f);
    runScene("torus knot 16x, directional", penumbra::scene::torusKnot(24), vec4(glm::normalize(vec3(0.3f, 1.0f, 0.4f)), 0.0f),
             16, 20.0f);
}

TEST_CASE("GPU stencil, far point light with scene_extent = the oracle's E: GPU == twin, edges found (issue 41)") {
    // A coarse epsilon 1e-3 with the light 1e3 away: uncapped, its coplanar reach (~1) swallows
    // every caster and nothing is flagged; capped at E the knot's shadow edges are.
    const penumbra::scene::Scene scene = penumbra::scene::torusKnot(24);
    const penumbra::scene::Mesh merged = scene.merged();
    const double extent = penumbra::reference::VisibilityOracle(merged.positions, merged.indices).sceneExtent();
    const vec3 centre = 0.5f * (scene.bounds().min + scene.bounds().max);
    const vec3 light = centre + 1e3f * glm::normalize(scene.light.position - centre);
    runScene("torus knot 8x, light at 1e3", scene, vec4(light, 1.0f), 8, 0.0f, 1e-3, extent);
}

TEST_CASE("GPU stencil: bad input returns a Status, setup errors throw") {
    penumbra::test::context();
    Frame f(penumbra::scene::columns(2), 16, 12);
    penumbra::AliasFreeHardOptions o;
    o.grid_width = 16;
    o.grid_height = 12;
    penumbra::gl::ShadowEdgeStencil stencil(16, 12, o);
    penumbra::SampleListsLight light;
    light.light = vec4(f.scene.light.position, 1.0f);
    light.view_projection = penumbra::lightViewProjectionForBounds(light.light, vec3(-2.0f, 0.0f, -2.0f), vec3(2.0f, 1.0f, 2.0f));
    penumbra::gl::Buffer small(64);
    auto whole = [](const penumbra::gl::Buffer& b) { return penumbra::BufferRange{b.id(), 0, b.size()}; };
    CHECK(stencil.writeSampleBuffer(penumbra::AaMode::Edge, whole(small), whole(small)) == penumbra::Status::NotReserved);
    CHECK(stencil.run(whole(small), f.normalRange(), f.view, light, f.casterBuffers()) == penumbra::Status::RangeTooSmall);
    penumbra::SampleListsView wrong = f.view;
    wrong.width = 8;
    CHECK(stencil.run(f.centreRange(), f.normalRange(), wrong, light, f.casterBuffers()) == penumbra::Status::InvalidArgument);
    penumbra::BufferRange odd = f.centreRange();
    odd.offset = 4;
    CHECK(stencil.run(odd, f.normalRange(), f.view, light, f.casterBuffers()) == penumbra::Status::Misaligned);
    REQUIRE(stencil.run(f.centreRange(), f.normalRange(), f.view, light, f.casterBuffers()) == penumbra::Status::Ok);
    CHECK(stencil.writeSampleBuffer(penumbra::AaMode::Off, whole(small), whole(small)) == penumbra::Status::InvalidArgument);
    CHECK(stencil.writeSampleBuffer(penumbra::AaMode::Edge, whole(small), whole(small)) == penumbra::Status::RangeTooSmall);
    CHECK(stencil.resolve(penumbra::AaMode::Full, whole(small), whole(small)) == penumbra::Status::RangeTooSmall);
    // Edge's resolve reads the ranks of a writeSampleBuffer(Edge) after this run: none yet.
    penumbra::gl::Buffer states(4ull * stencil.sampleCount(penumbra::AaMode::Full)), visible(4ull * 16 * 12);
    CHECK(stencil.resolve(penumbra::AaMode::Edge, whole(states), whole(visible)) == penumbra::Status::NotReserved);
    penumbra::gl::Buffer pos(stencil.sampleBufferBytes()), nrm(stencil.sampleBufferBytes());
    REQUIRE(stencil.writeSampleBuffer(penumbra::AaMode::Edge, whole(pos), whole(nrm)) == penumbra::Status::Ok);
    CHECK(stencil.resolve(penumbra::AaMode::Edge, whole(states), whole(visible)) == penumbra::Status::Ok);
    REQUIRE(stencil.run(f.centreRange(), f.normalRange(), f.view, light, f.casterBuffers()) == penumbra::Status::Ok);
    CHECK(stencil.resolve(penumbra::AaMode::Edge, whole(states), whole(visible)) == penumbra::Status::NotReserved);

    penumbra::AaPatternOptions jittered;
    jittered.pattern = penumbra::AaPattern::Jittered;
    CHECK_THROWS_WITH_AS(penumbra::gl::ShadowEdgeStencil(16, 12, o, jittered), doctest::Contains("rotated-grid"), penumbra::Error);
    penumbra::AliasFreeHardOptions culled = o;
    culled.light_facing_only = true;
    CHECK_THROWS_WITH_AS(penumbra::gl::ShadowEdgeStencil(16, 12, culled), doctest::Contains("without caster culling"),
                         penumbra::Error);
    CHECK_THROWS_WITH_AS(penumbra::gl::ShadowEdgeStencil(0, 12, o), doctest::Contains("view 0x12"), penumbra::Error);
}
