// View-sample lists (sintorn2008 §3.1) on the view samples of real scenes: the scene is rendered
// from its camera into a depth (GL_DEPTH_COMPONENT32F) + world-normal G-buffer, which feeds the
// builder's depth input (the engine path); the light frustum is first aimed at the scene and then
// fitted to the samples (§4.3), as the seed does before every pass. The light grid has the view's
// size (the seed's Fig. 9 setting at 512^2; a same-size grid keeps about one sample per occupied
// texel in the fitted frustum, which is what the alias-free shadow map wants).
//
//   BM_SampleLists/<w>          count + scan + scatter for a w x w view and light grid (torus
//                               knot); GPU time (GL_TIME_ELAPSED, or the glFinish wall time where
//                               the timer is meaningless, as on llvmpipe), manual time. Counters:
//                               samples_per_second (view samples / GPU second), Fig. 9 list
//                               statistics (occupancy %, avg_list_length over occupied lists,
//                               avg_list_length_all, max_list_length), accepted and rejected_* by
//                               reason, err_structure (1 when the GPU structure differs from the
//                               CPU twin's modulo list order, else 0).
//   BM_SampleListsFit/<w>       the §4.3 fit reduction alone.
//   BM_SampleListsStats/<scene>/512   Fig. 9 statistics for torus_knot and hairball at 512^2 with
//                               the fitted frustum, plus the same before fitting (*_unfitted);
//                               timed: the statistics reduction.
// Smoke runs (PENUMBRA_BENCH_SMOKE=1) use 32^2 / 64^2.
#include "bench_common.hpp"

#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/shader.hpp>
#include <penumbra/gl/sample_lists.hpp>
#include <penumbra/scene/scene.hpp>

#include <benchmark/benchmark.h>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

namespace {

namespace gl = penumbra::gl;
using penumbra::bench::timeGpu;

const char* const kGBufferVertex = R"(#version 450
layout(location = 0) in vec3 benchPosition;
layout(location = 1) in vec3 benchNormal;
layout(location = 0) uniform mat4 benchViewProjection;
layout(location = 0) out vec3 benchWorldNormal;
void main() {
    benchWorldNormal = benchNormal;
    gl_Position = benchViewProjection * vec4(benchPosition, 1.0);
}
)";

// Two-sided: open meshes (hairball slivers) show their back faces with the normal flipped.
const char* const kGBufferFragment = R"(#version 450
layout(location = 0) in vec3 benchWorldNormal;
layout(location = 0) out vec4 benchNormalOut;
void main() {
    vec3 n = normalize(benchWorldNormal);
    benchNormalOut = vec4(gl_FrontFacing ? n : -n, 0.0);
}
)";

/// The scene's camera view as a depth + world-normal G-buffer of w x w pixels.
struct GBuffer {
    uint32_t size = 0;
    gl::Texture depth{GL_TEXTURE_2D}, normals{GL_TEXTURE_2D};
    penumbra::SampleListsView view;

    GBuffer(const penumbra::scene::Scene& scene, uint32_t w) : size(w) {
        const penumbra::scene::Mesh mesh = scene.merged();
        auto positions = gl::Buffer::fromVector(mesh.positions);
        auto normal_buffer = gl::Buffer::fromVector(mesh.normals);
        auto indices = gl::Buffer::fromVector(mesh.indices);
        penumbra::ShaderLibrary library;
        library.add("bench/gbuffer.vert.glsl", kGBufferVertex);
        library.add("bench/gbuffer.frag.glsl", kGBufferFragment);
        gl::Program program = gl::buildProgram({"bench/gbuffer.vert.glsl", "bench/gbuffer.frag.glsl"}, {}, library);

        glTextureStorage2D(depth.id(), 1, GL_DEPTH_COMPONENT32F, GLsizei(w), GLsizei(w));
        glTextureStorage2D(normals.id(), 1, GL_RGBA32F, GLsizei(w), GLsizei(w));
        GLuint fbo = 0, vao = 0;
        glCreateFramebuffers(1, &fbo);
        glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, depth.id(), 0);
        glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, normals.id(), 0);
        PENUMBRA_CHECK(glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE,
                       "sample_lists_bench: G-buffer framebuffer incomplete");
        glCreateVertexArrays(1, &vao);
        glVertexArrayVertexBuffer(vao, 0, positions.id(), 0, sizeof(glm::vec3));
        glVertexArrayVertexBuffer(vao, 1, normal_buffer.id(), 0, sizeof(glm::vec3));
        glVertexArrayElementBuffer(vao, indices.id());
        for (GLuint a = 0; a < 2; ++a) {
            glEnableVertexArrayAttrib(vao, a);
            glVertexArrayAttribFormat(vao, a, 3, GL_FLOAT, GL_FALSE, 0);
            glVertexArrayAttribBinding(vao, a, a);
        }
        const glm::mat4 view_projection = scene.camera.projection(1.0f) * scene.camera.view();
        view.width = view.height = w;
        view.inverse_view_projection = glm::inverse(view_projection);

        glBindFramebuffer(GL_FRAMEBUFFER, fbo);
        glViewport(0, 0, GLsizei(w), GLsizei(w));
        const float clear_normal[4] = {0, 0, 0, 0};
        const float clear_depth = 1.0f;
        glClearNamedFramebufferfv(fbo, GL_COLOR, 0, clear_normal);
        glClearNamedFramebufferfv(fbo, GL_DEPTH, 0, &clear_depth);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glDisable(GL_CULL_FACE);
        program.use();
        glUniformMatrix4fv(0, 1, GL_FALSE, &view_projection[0][0]);
        glBindVertexArray(vao);
        glDrawElements(GL_TRIANGLES, GLsizei(mesh.indices.size()), GL_UNSIGNED_INT, nullptr);
        glDisable(GL_DEPTH_TEST);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glDeleteFramebuffers(1, &fbo);
        glDeleteVertexArrays(1, &vao);
        gl::checkErrors("sample_lists_bench G-buffer");
    }

    penumbra::SampleDepthInput input() const { return {depth.id(), normals.id(), view}; }

    std::vector<float> downloadDepth() const {
        std::vector<float> out(size_t(size) * size);
        glGetTextureImage(depth.id(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(out.size() * 4), out.data());
        return out;
    }
    std::vector<glm::vec4> downloadNormals() const {
        std::vector<glm::vec4> out(size_t(size) * size);
        glGetTextureImage(normals.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(out.size() * 16), out.data());
        return out;
    }
};

/// A perspective light at the scene's light position aimed at the object, wide enough for every
/// corner of the scene's bounds (capped at 150 degrees); far = the farthest corner. The §4.3 fit
/// then crops it to the view samples.
penumbra::SampleListsLight aimedLight(const penumbra::scene::Scene& scene) {
    const glm::vec3 eye = scene.light.position;
    const glm::vec3 target = scene.meshes.back().bounds().center();
    const glm::vec3 axis = glm::normalize(target - eye);
    const glm::vec3 up = std::abs(axis.y) > 0.99f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
    const penumbra::scene::Bounds box = scene.bounds();
    float max_angle = 0.0f, far_plane = 0.0f;
    for (int c = 0; c < 8; ++c) {
        const glm::vec3 corner((c & 1) ? box.max.x : box.min.x, (c & 2) ? box.max.y : box.min.y,
                               (c & 4) ? box.max.z : box.min.z);
        const glm::vec3 v = corner - eye;
        const float d = glm::length(v);
        far_plane = std::max(far_plane, d);
        max_angle = std::max(max_angle, std::acos(std::clamp(glm::dot(v / d, axis), -1.0f, 1.0f)));
    }
    const float fov = std::min(2.0f * max_angle * 1.02f, glm::radians(150.0f));
    penumbra::SampleListsLight light;
    light.view_projection = glm::perspective(fov, 1.0f, 0.02f * glm::length(target - eye), 1.01f * far_plane) *
                            glm::lookAt(eye, target, up);
    light.light = glm::vec4(eye, 1.0f);
    return light;
}

struct ListBuffers {
    gl::Buffer counts, offsets, list_positions, list_ids, sample_slots, sample_texels, header, frustum;
    explicit ListBuffers(const penumbra::SampleListsSetup& s)
        : counts(s.counts_bytes), offsets(s.offsets_bytes), list_positions(s.list_positions_bytes),
          list_ids(s.list_ids_bytes), sample_slots(s.sample_slots_bytes), sample_texels(s.sample_texels_bytes),
          header(s.header_bytes), frustum(sizeof(penumbra::SampleListsFrustum)) {}
    penumbra::SampleListsBuffers ids() const {
        auto r = [](const gl::Buffer& b) { return penumbra::BufferRange{b.id(), 0, b.size()}; };
        return {r(counts),       r(offsets),       r(list_positions), r(list_ids),
                r(sample_slots), r(sample_texels), r(header),         r(frustum)};
    }
};

penumbra::SampleListsBuild withFit() {
    penumbra::SampleListsBuild b;
    b.fit_frustum = true;
    return b;
}

void setStatistics(benchmark::State& state, const penumbra::SampleListStatistics& s, const std::string& suffix = "") {
    state.counters["occupancy" + suffix] = 100.0 * s.occupancy();
    state.counters["avg_list_length" + suffix] = s.averageOccupiedLength();
    state.counters["avg_list_length_all" + suffix] = s.averageLength();
    state.counters["max_list_length" + suffix] = s.max_list_length;
    state.counters["accepted" + suffix] = s.accepted;
    for (uint32_t r = 0; r < penumbra::kSampleListsReasonCount; ++r) {
        state.counters[std::string("rejected_") + penumbra::sampleRejectionName(penumbra::SampleRejection(r)) + suffix] =
            s.rejected[r];
    }
}

/// One scene at one size: G-buffer, aimed light, GPU-fitted light, buffers.
struct Fixture {
    penumbra::scene::Scene scene;
    GBuffer gbuffer;
    penumbra::SampleListsSetup setup;
    penumbra::SampleListsLight aimed, fitted;
    ListBuffers lists;
    penumbra::SampleListBuilder builder;

    Fixture(const std::string& name, uint32_t w)
        : scene(penumbra::scene::builtin(name)), gbuffer(scene, w),
          setup(penumbra::sampleListsSetup(w, w, uint64_t(w) * w)), aimed(aimedLight(scene)), fitted(aimed),
          lists(setup) {
        builder.reserve(setup);
        builder.validate(setup, gbuffer.input(), lists.ids());
        builder.build(setup, aimed, gbuffer.input(), lists.ids(), {}, withFit());
        fitted.view_projection = penumbra::SampleListBuilder::readFrustum(lists.ids().frustum).view_projection;
    }

    penumbra::SampleListStatistics statistics() {
        builder.statistics(setup, lists.ids());
        return penumbra::SampleListBuilder::readStatistics(setup, lists.ids());
    }

    /// 1 when the GPU structure for `light` differs from the CPU twin's (modulo list order).
    double structureError(const penumbra::SampleListsLight& light) {
        builder.build(setup, light, gbuffer.input(), lists.ids());
        const auto gpu = penumbra::downloadSampleLists(setup, lists.ids());
        const auto depth = gbuffer.downloadDepth();
        const auto normals = gbuffer.downloadNormals();
        const auto cpu = penumbra::buildSampleListsCpu(setup, light, gbuffer.view, depth.data(), normals.data());
        const std::string diff = penumbra::sampleListsDifference(gpu, cpu);
        return diff.empty() ? 0.0 : 1.0;
    }
};

void BM_SampleLists(benchmark::State& state, uint32_t w) {
    penumbra::bench::glContext();
    Fixture f("torus_knot", w);
    const double err = f.structureError(f.fitted);
    for (int warm = 0; warm < 2; ++warm) f.builder.build(f.setup, f.fitted, f.gbuffer.input(), f.lists.ids());
    glFinish();
    double seconds = 0.0;
    uint64_t samples = 0;
    for (auto _ : state) {
        const double s = timeGpu([&] { f.builder.build(f.setup, f.fitted, f.gbuffer.input(), f.lists.ids()); });
        state.SetIterationTime(s);
        seconds += s;
        samples += f.setup.sample_count;
    }
    state.counters["samples_per_second"] = seconds > 0 ? double(samples) / seconds : 0.0;
    state.counters["lists"] = f.setup.lists;
    setStatistics(state, f.statistics());
    state.counters["err_structure"] = err;
    state.counters["timer_gl_time_elapsed"] = penumbra::bench::timerCounter();
}

// The §4.3 fit on the GPU (fit + resolve passes, then the lists built with the fitted frustum in
// the same call: nothing read back) against the same build with the light's own frustum.
void BM_SampleListsFit(benchmark::State& state, uint32_t w) {
    penumbra::bench::glContext();
    Fixture f("torus_knot", w);
    for (int warm = 0; warm < 2; ++warm) f.builder.build(f.setup, f.aimed, f.gbuffer.input(), f.lists.ids(), {}, withFit());
    double seconds = 0.0, unfitted = 0.0;
    uint64_t samples = 0;
    for (auto _ : state) {
        const double s = timeGpu([&] { f.builder.build(f.setup, f.aimed, f.gbuffer.input(), f.lists.ids(), {}, withFit()); });
        state.PauseTiming();
        unfitted += timeGpu([&] { f.builder.build(f.setup, f.aimed, f.gbuffer.input(), f.lists.ids()); });
        state.ResumeTiming();
        state.SetIterationTime(s);
        seconds += s;
        samples += f.setup.sample_count;
    }
    state.counters["samples_per_second"] = seconds > 0 ? double(samples) / seconds : 0.0;
    state.counters["fitted_over_unfitted_time"] = unfitted > 0 ? seconds / unfitted : 0.0;
    // err: the GPU fit must equal the CPU twin's bit for bit (outside the timed region).
    f.builder.build(f.setup, f.aimed, f.gbuffer.input(), f.lists.ids(), {}, withFit());
    const auto gpu = penumbra::SampleListBuilder::readFrustum(f.lists.ids().frustum);
    const auto depth = f.gbuffer.downloadDepth();
    const auto normals = f.gbuffer.downloadNormals();
    const auto cpu = penumbra::fitLightFrustumCpu(f.setup, f.aimed, f.gbuffer.view, depth.data(), normals.data());
    state.counters["err_fit"] = std::memcmp(&gpu, &cpu.frustum, sizeof gpu) == 0 ? 0 : 1;
    state.counters["fit_box_area"] = double(gpu.box.z - gpu.box.x) * double(gpu.box.w - gpu.box.y);
    state.counters["timer_gl_time_elapsed"] = penumbra::bench::timerCounter();
}

void BM_SampleListsStats(benchmark::State& state, const std::string& scene, uint32_t w) {
    penumbra::bench::glContext();
    Fixture f(scene, w);
    f.builder.build(f.setup, f.aimed, f.gbuffer.input(), f.lists.ids());
    setStatistics(state, f.statistics(), "_unfitted");
    f.builder.build(f.setup, f.fitted, f.gbuffer.input(), f.lists.ids());
    for (auto _ : state) {
        state.SetIterationTime(timeGpu([&] { f.builder.statistics(f.setup, f.lists.ids()); }));
    }
    setStatistics(state, f.statistics());
    state.counters["err_structure"] = f.structureError(f.fitted);
}

const bool kRegistered = [] {
    const bool smoke = penumbra::bench::smokeRun();
    const std::vector<uint32_t> sizes = smoke ? std::vector<uint32_t>{32} : std::vector<uint32_t>{128, 256, 512, 1024};
    for (uint32_t w : sizes) {
        benchmark::RegisterBenchmark(("BM_SampleLists/" + std::to_string(w)).c_str(), BM_SampleLists, w)
            ->UseManualTime()
            ->Unit(benchmark::kMillisecond);
    }
    for (uint32_t w : sizes) {
        benchmark::RegisterBenchmark(("BM_SampleListsFit/" + std::to_string(w)).c_str(), BM_SampleListsFit, w)
            ->UseManualTime()
            ->Unit(benchmark::kMillisecond);
    }
    const uint32_t stats_size = smoke ? 64 : 512;
    for (const char* scene : {"torus_knot", "hairball"}) {
        benchmark::RegisterBenchmark(("BM_SampleListsStats/" + std::string(scene) + "/" + std::to_string(stats_size)).c_str(),
                                     BM_SampleListsStats, std::string(scene), stats_size)
            ->UseManualTime()
            ->Unit(benchmark::kMillisecond);
    }
    return true;
}();

}  // namespace
