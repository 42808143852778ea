// Conservative raster (sintorn2008 §3.2): the seed's fixed 6-vertex emitter through its two-pass
// plan (direct pass declaring max_vertices 6 + the indirect spill pass for triangles that need
// clipping), the same emitter in one pass (max_vertices 13), the exact hull and the plain
// (non-conservative) raster as a baseline, drawing the same random triangles (0.3 .. 24 px,
// anywhere in a 1024^2 viewport) into an R32UI id target. The `near25` scene moves one vertex of a
// quarter of them behind the near plane (z = -1.25 w): they stay inside their pixel footprint but
// need clipping, i.e. the spill pass. GPU time is glFinish-bounded around the frame's draws (the
// plan: header reset, direct draw, barrier, indirect draw) after a warm-up (manual time). Error
// counters come from one recorded frame per benchmark (PENUMBRA_CONSERVATIVE_RECORD), read back
// outside the timed region and checked against the exact predicate:
//   err_missed        pixels the contract requires that got no fragment (must be 0 for fixed6/exact;
//                     the plain baseline shows why conservative raster is needed),
//   err_overcoverage  extra fragments (not required, or duplicates) / required pixels,
//   err_overcoverage_per_triangle  the same extra fragments / triangles,
//   err_spill_mismatch |triangles the GPU spilled - triangles conservativeNeedsSpill() predicts|,
//   spill_fraction    triangles through the spill pass / triangles (plan: the GPU header's count;
//                     0 for the single-pass modes, which have no spill pass),
//   gs_max_vertices   what the (direct) geometry stage declares,
//   time_vs_single_pass (plan only) this entry's time / the single pass's, both timed here,
//   fragments_per_triangle, vertices_per_triangle (what the geometry stages emit, CPU twin),
//   triangles_per_second.
#include "bench_common.hpp"

#include <penumbra/conservative_raster.hpp>
#include <penumbra/gl/conservative_raster.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/shader.hpp>

#include <benchmark/benchmark.h>

#include <bitset>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

namespace {

enum class Mode { Fixed6, Fixed6Single, Exact, Plain };

struct Scene {
    int size = 0;
    std::vector<glm::vec4> vertices;  // clip space, 3 per triangle
    std::vector<glm::ivec2> tiles;    // per triangle (window pixels), for the recorded pass
};

Scene makeScene(size_t count, int size, double near_fraction) {
    Scene scene;
    scene.size = size;
    std::mt19937 rng(20080615u);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (size_t i = 0; i < count; ++i) {
        const double extent = std::pow(10.0, -0.5 + 1.88 * u(rng));  // 0.3 .. 24 px
        const glm::dvec2 base = glm::dvec2(u(rng), u(rng)) * (size - 30.0) + 3.0;
        glm::dvec2 lo(1e300);
        for (int k = 0; k < 3; ++k) {
            const glm::dvec2 p = base + extent * glm::dvec2(u(rng), u(rng));
            const double w = 0.5 + u(rng);
            scene.vertices.emplace_back(static_cast<float>((p.x / size * 2 - 1) * w), static_cast<float>((p.y / size * 2 - 1) * w),
                                        static_cast<float>((u(rng) - 0.5) * w), static_cast<float>(w));
            lo = glm::min(lo, p);
        }
        scene.tiles.push_back(glm::ivec2(glm::floor(lo)) - 3);
        // Behind the near plane (z < -w) with the same x, y, w: the clipped part projects inside the
        // triangle's own footprint, so the 32 x 32 record tile still holds it.
        if (u(rng) < near_fraction) scene.vertices.back().z = -1.25f * scene.vertices.back().w;
    }
    return scene;
}

constexpr const char* kVert = "penumbra/conservative_raster/conservative_raster.vert.glsl";
constexpr const char* kGeom = "penumbra/conservative_raster/conservative_raster.geom.glsl";
constexpr const char* kFrag = "penumbra/conservative_raster/conservative_raster.frag.glsl";

// pass: 0 = the (direct) pass drawing the scene, 1 = the plan's spill pass.
penumbra::gl::Program buildProgram(Mode mode, const penumbra::ConservativeRasterSetup& setup, bool record, int pass = 0) {
    penumbra::ShaderDefines defines = mode != Mode::Fixed6 ? setup.defines
                                      : pass == 0          ? setup.spill.direct_defines
                                                           : setup.spill.spill_defines;
    defines.push_back({"PENUMBRA_CONSERVATIVE_RECORD", record ? "1" : "0"});
    if (mode == Mode::Plain) {
        defines.push_back({"PENUMBRA_CONSERVATIVE_PLAIN", "1"});
        return penumbra::gl::buildProgram({"penumbra/conservative_raster/conservative_raster.vert.glsl",
                                           "penumbra/conservative_raster/conservative_raster.frag.glsl"},
                                          defines);
    }
    return penumbra::gl::buildProgram({kVert, kGeom, kFrag}, defines);
}

// What one frame needs: the programs, the plan's spill buffer and an empty vertex array.
struct Frame {
    Mode mode;
    const penumbra::ConservativeRasterSetup* setup;
    penumbra::gl::Program direct, spill;
    penumbra::gl::Buffer spill_buffer;
    GLuint vao = 0, empty_vao = 0;
    GLsizei vertex_count = 0;

    Frame(Mode m, const penumbra::ConservativeRasterSetup& s, bool record, GLuint scene_vao, GLsizei vertices)
        : mode(m), setup(&s), direct(buildProgram(m, s, record, 0)),
          spill(m == Mode::Fixed6 ? buildProgram(m, s, record, 1) : penumbra::gl::Program()),
          spill_buffer(m == Mode::Fixed6 ? static_cast<size_t>(s.spill.buffer_bytes) : 64), vao(scene_vao),
          vertex_count(vertices) {
        glCreateVertexArrays(1, &empty_vao);
    }
    ~Frame() { glDeleteVertexArrays(1, &empty_vao); }

    // The per-frame work: (plan) reset the header, direct draw, barrier, indirect spill draw.
    void draw() {
        const penumbra::BufferRange range{spill_buffer.id(), 0, setup->spill.buffer_bytes};
        if (mode == Mode::Fixed6) penumbra::gl::beginConservativeSpill(*setup, range);
        direct.use();
        glUniform1ui(8, 0u);
        glBindVertexArray(vao);
        glDrawArrays(GL_TRIANGLES, 0, vertex_count);
        if (mode == Mode::Fixed6) {
            spill.use();
            glBindVertexArray(empty_vao);
            penumbra::gl::drawConservativeSpill(*setup, range);
        }
    }

    /// Triangles the last frame spilled (read back: outside timed regions only).
    double spilled() const {
        if (mode != Mode::Fixed6) return 0;
        const penumbra::ConservativeSpillHeader header =
            penumbra::gl::readConservativeSpillHeader({spill_buffer.id(), 0, setup->spill.buffer_bytes});
        return static_cast<double>(header.count / 3u + header.overflow);
    }
};

struct ErrorCounts {
    double required = 0, fragments = 0, extra = 0, missed = 0, vertices = 0, spilled = 0, spill_predicted = 0;
};

// One recorded draw, checked per triangle against the exact predicate.
ErrorCounts measureErrors(Mode mode, const penumbra::ConservativeRasterSetup& setup, const Scene& scene, GLuint vao) {
    const size_t n = scene.tiles.size();
    constexpr int kWords = PENUMBRA_CONSERVATIVE_RECORD_WORDS;
    Frame frame(mode, setup, true, vao, static_cast<GLsizei>(3 * n));
    auto tiles = penumbra::gl::Buffer::fromVector(scene.tiles);
    penumbra::gl::Buffer words(n * kWords * sizeof(uint32_t));
    penumbra::gl::Buffer clips(3 * n * sizeof(glm::vec4));
    words.fill(0u);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_CONSERVATIVE_RECORD_WORDS_BINDING, words.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_CONSERVATIVE_RECORD_TILES_BINDING, tiles.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_CONSERVATIVE_RECORD_CLIP_BINDING, clips.id());
    frame.draw();
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    const std::vector<uint32_t> recorded = words.download<uint32_t>();
    ErrorCounts e;
    e.spilled = frame.spilled();
    for (size_t t = 0; t < n; ++t) {
        const glm::vec4* c = &scene.vertices[3 * t];
        const uint32_t* w = &recorded[t * kWords];
        const glm::ivec2 tile = scene.tiles[t] - glm::ivec2(setup.options.viewport_x, setup.options.viewport_y);
        const auto required = penumbra::conservativeRequiredPixels(c[0], c[1], c[2], setup);
        uint32_t required_bits[PENUMBRA_CONSERVATIVE_RECORD_TILE] = {};
        for (const auto& p : required) {
            const glm::ivec2 l = p - tile;
            if (l.x < 0 || l.y < 0 || l.x >= PENUMBRA_CONSERVATIVE_RECORD_TILE || l.y >= PENUMBRA_CONSERVATIVE_RECORD_TILE) {
                e.missed += 1;  // cannot happen with these scenes; counted as missed to be safe
                continue;
            }
            required_bits[l.y] |= 1u << l.x;
        }
        double covered = 0;
        for (int r = 0; r < PENUMBRA_CONSERVATIVE_RECORD_TILE; ++r) {
            covered += static_cast<double>(std::bitset<32>(w[r]).count());
            e.missed += static_cast<double>(std::bitset<32>(required_bits[r] & ~w[r]).count());
            e.extra += static_cast<double>(std::bitset<32>(w[r] & ~required_bits[r]).count());
        }
        const double fragments = w[PENUMBRA_CONSERVATIVE_RECORD_FRAGMENTS];
        e.extra += fragments - covered;  // duplicates and fragments outside the tile
        e.fragments += fragments;
        e.required += static_cast<double>(required.size());
        e.vertices += mode == Mode::Plain ? 3 : penumbra::conservativeHull(c[0], c[1], c[2], setup).count;
        e.spill_predicted += penumbra::conservativeNeedsSpill(c[0], c[1], c[2], setup);
    }
    penumbra::gl::checkErrors("conservative raster bench record");
    return e;
}

void BM_ConservativeRaster(benchmark::State& state, Mode mode, double near_fraction) {
    penumbra::bench::glContext();
    const bool smoke = penumbra::bench::smokeRun();
    const size_t count = smoke ? 1024 : 65536;
    const int size = smoke ? 256 : 1024;
    static const Scene screen = makeScene(count, size, 0.0);  // the same triangles for every mode
    static const Scene near25 = makeScene(count, size, 0.25);
    const Scene& scene = near_fraction > 0 ? near25 : screen;

    penumbra::ConservativeRasterOptions options;
    options.viewport_width = options.viewport_height = size;
    options.variant = mode == Mode::Exact ? penumbra::ConservativeVariant::Exact : penumbra::ConservativeVariant::Fixed6;
    options.subpixel_bits = penumbra::gl::getInteger(GL_SUBPIXEL_BITS);
    options.max_triangles = static_cast<uint32_t>(count);  // the spill buffer can never overflow
    const penumbra::ConservativeRasterSetup setup = penumbra::conservativeRasterSetup(options);

    auto vbo = penumbra::gl::Buffer::fromVector(scene.vertices);
    penumbra::gl::Buffer params(sizeof(setup.params), &setup.params);
    penumbra::gl::Texture ids(GL_TEXTURE_2D);
    glTextureStorage2D(ids.id(), 1, GL_R32UI, size, size);
    GLuint fbo = 0, vao = 0;
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, ids.id(), 0);
    glCreateVertexArrays(1, &vao);
    glVertexArrayVertexBuffer(vao, 0, vbo.id(), 0, sizeof(glm::vec4));
    glVertexArrayAttribFormat(vao, 0, 4, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(vao, 0, 0);
    glEnableVertexArrayAttrib(vao, 0);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, size, size);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glBindBufferBase(GL_UNIFORM_BUFFER, PENUMBRA_CONSERVATIVE_PARAMS_BINDING, params.id());

    const ErrorCounts errors = measureErrors(mode, setup, scene, vao);

    const GLsizei vertex_count = static_cast<GLsizei>(3 * count);
    Frame frame(mode, setup, false, vao, vertex_count);
    // The plan's baseline, timed in this entry too: the same emitter in one pass (max_vertices 13).
    std::unique_ptr<Frame> single;
    if (mode == Mode::Fixed6) single = std::make_unique<Frame>(Mode::Fixed6Single, setup, false, vao, vertex_count);
    frame.draw();  // warm-up
    if (single) single->draw();
    glFinish();
    double time = 0, single_time = 0;
    for (auto _ : state) {
        const double t = penumbra::bench::timeGpu([&] { frame.draw(); });
        state.SetIterationTime(t);
        time += t;
        if (single) single_time += penumbra::bench::timeGpu([&] { single->draw(); });
    }
    penumbra::gl::checkErrors("conservative raster bench");
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &fbo);
    glDeleteVertexArrays(1, &vao);

    const double n = static_cast<double>(count);
    state.counters["triangles_per_second"] = benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate);
    penumbra::bench::reportTimer(state);  // which clock timed this entry
    state.counters["fragments_per_triangle"] = errors.fragments / n;
    state.counters["vertices_per_triangle"] = errors.vertices / n;
    state.counters["err_overcoverage"] = errors.extra / std::max(errors.required, 1.0);
    state.counters["err_overcoverage_per_triangle"] = errors.extra / n;
    state.counters["err_missed"] = errors.missed;
    state.counters["err_spill_mismatch"] = std::abs(errors.spilled - (mode == Mode::Fixed6 ? errors.spill_predicted : 0.0));
    state.counters["spill_fraction"] = errors.spilled / n;
    state.counters["gs_max_vertices"] = mode == Mode::Plain    ? 0
                                        : mode == Mode::Fixed6 ? setup.spill.direct_max_vertices
                                                               : setup.max_vertices;
    if (single) state.counters["time_vs_single_pass"] = time / std::max(single_time, 1e-12);
    state.SetLabel(std::to_string(count) + " triangles in " + std::to_string(size) + "^2");
}

BENCHMARK_CAPTURE(BM_ConservativeRaster, fixed6, Mode::Fixed6, 0.0)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ConservativeRaster, fixed6_single_pass, Mode::Fixed6Single, 0.0)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ConservativeRaster, exact, Mode::Exact, 0.0)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ConservativeRaster, plain, Mode::Plain, 0.0)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ConservativeRaster, fixed6_near25, Mode::Fixed6, 0.25)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ConservativeRaster, fixed6_single_pass_near25, Mode::Fixed6Single, 0.25)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ConservativeRaster, exact_near25, Mode::Exact, 0.25)->UseManualTime()->Unit(benchmark::kMillisecond);

}  // namespace
