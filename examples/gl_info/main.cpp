// gl_info — what the headless GL context penumbra gets on this machine can do, as one JSON line.
//
//   gl_info            (backend from PENUMBRA_GL, as every test: egl | osmesa | unset = EGL then OSMesa)
//
// The first step of tools/gpu_bundle.sh's run.sh: a results folder from another machine starts
// with the driver that produced it (platform egl-device / egl-surfaceless / osmesa, vendor,
// renderer, version) and the capabilities penumbra's blocks choose paths by (subgroups for the
// scan, fp64 for the blocker test's fallback, timer queries for the benchmarks' GPU times).
// Exit codes: 0 done, 1 no GL 4.5 core context (the reason on stderr).
#include <penumbra/gl/headless.hpp>
#include <penumbra/gl/scan.hpp>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <exception>
#include <string>

namespace {

std::string glString(GLenum name) {
    const char* s = reinterpret_cast<const char*>(glGetString(name));
    return s ? s : "";
}

int64_t getInteger64(GLenum name) {
    GLint64 value = 0;
    glGetInteger64v(name, &value);
    return static_cast<int64_t>(value);
}

/// Whether a GL_TIME_ELAPSED query around real GPU work reports a duration: the counter has bits
/// and its answer lies between 5% and 102% of the glFinish-to-glFinish wall time (the test
/// benchmarks/bench_common.hpp's timeGpu applies; llvmpipe answers 1 ns or no duration).
nlohmann::ordered_json timerQuery() {
    GLint bits = 0;
    glGetQueryiv(GL_TIME_ELAPSED, GL_QUERY_COUNTER_BITS, &bits);
    nlohmann::ordered_json out = {{"counter_bits", bits}};
    // Work to time: clears of a 2048 x 2048 RGBA32F renderbuffer (64 MiB each), no shader needed.
    GLuint rb = 0, fbo = 0, query = 0;
    glCreateRenderbuffers(1, &rb);
    glNamedRenderbufferStorage(rb, GL_RGBA32F, 2048, 2048);
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferRenderbuffer(fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb);
    glCreateQueries(GL_TIME_ELAPSED, 1, &query);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, 2048, 2048);
    glFinish();
    const auto start = std::chrono::steady_clock::now();
    glBeginQuery(GL_TIME_ELAPSED, query);
    for (int i = 0; i < 16; ++i) {
        const float colour[4] = {float(i), 0.0f, 0.0f, 1.0f};
        glClearNamedFramebufferfv(fbo, GL_COLOR, 0, colour);
    }
    glEndQuery(GL_TIME_ELAPSED);
    glFinish();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    GLuint64 ns = 0;
    glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteQueries(1, &query);
    glDeleteFramebuffers(1, &fbo);
    glDeleteRenderbuffers(1, &rb);
    const double measured = double(ns) * 1e-9;
    out["wall_ms"] = wall * 1e3;
    out["query_ms"] = measured * 1e3;
    out["measures"] = bits > 0 && measured >= 0.05 * wall && measured <= 1.02 * wall;
    return out;
}

}  // namespace

int main() {
    try {
        penumbra::gl::HeadlessOptions options;
        options.debug = false;  // a plain context: what benchmarks measure on
        penumbra::gl::HeadlessContext context(options);
        const bool khr_subgroup = context.hasExtension("GL_KHR_shader_subgroup");
        nlohmann::ordered_json j;
        j["backend"] = penumbra::gl::backendName(context.backend());
        j["platform"] = context.platform();
        j["vendor"] = glString(GL_VENDOR);
        j["renderer"] = glString(GL_RENDERER);
        j["version"] = glString(GL_VERSION);
        j["glsl_version"] = glString(GL_SHADING_LANGUAGE_VERSION);
        j["khr_shader_subgroup"] = khr_subgroup;
        // GL_SUBGROUP_SIZE_KHR as the driver reports it, and the size the scan uses (0: the
        // driver lacks compute basic + arithmetic subgroup operations; see gl/scan.hpp).
        j["subgroup_size"] = khr_subgroup ? penumbra::gl::getInteger(GL_SUBGROUP_SIZE_KHR) : 0;
        j["scan_subgroup_size"] = penumbra::detail::computeSubgroupSize();
        j["arb_gpu_shader_fp64"] = context.hasExtension("GL_ARB_gpu_shader_fp64");
        j["arb_shader_ballot"] = context.hasExtension("GL_ARB_shader_ballot");
        j["time_elapsed"] = timerQuery();
        j["max_ssbo_bytes"] = getInteger64(GL_MAX_SHADER_STORAGE_BLOCK_SIZE);
        j["max_compute_invocations"] = penumbra::gl::getInteger(GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS);
        j["max_compute_shared_bytes"] = penumbra::gl::getInteger(GL_MAX_COMPUTE_SHARED_MEMORY_SIZE);
        j["max_texture_size"] = penumbra::gl::getInteger(GL_MAX_TEXTURE_SIZE);
        j["gl_error"] = penumbra::gl::errorName(glGetError());
        std::printf("%s\n", j.dump().c_str());
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "gl_info: no GL 4.5 core context: %s\n", e.what());
        return 1;
    }
}
