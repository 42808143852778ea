// An engine-style consumer: its own EGL context (surfaceless, no penumbra::headless), libepoxy as
// the GL loader (PENUMBRA_GL_HEADER=<epoxy/gl.h>), its own buffers and vertex arrays. Runs the
// scan, the sample-list builder and the hard-shadow pipeline and checks them against the CPU
// twins and the oracle. Exit code 0 = pass; 77 = no EGL display here (skipped).
#include <epoxy/egl.h>  // epoxy's EGL declarations (the Khronos EGL headers clash with epoxy/gl.h)
#include <epoxy/gl.h>

#include <penumbra/gl/pipelines/alias_free_hard.hpp>
#include <penumbra/gl/sample_lists.hpp>
#include <penumbra/gl/scan.hpp>
#include <penumbra/reference/visibility.hpp>

#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

namespace {

bool makeContext() {
    EGLDisplay display = epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_MESA_platform_surfaceless")
                             ? eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr)
                             : eglGetDisplay(EGL_DEFAULT_DISPLAY);
    if (display == EGL_NO_DISPLAY || !eglInitialize(display, nullptr, nullptr)) return false;
    if (!eglBindAPI(EGL_OPENGL_API)) return false;
    const EGLint config_attributes[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint configs = 0;
    eglChooseConfig(display, config_attributes, &config, 1, &configs);
    const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                         EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                         EGL_NONE};
    EGLContext context = eglCreateContext(display, configs ? config : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, context_attributes);
    return context != EGL_NO_CONTEXT && eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context);
}

penumbra::BufferRange range(GLuint buffer, size_t bytes) { return {buffer, 0, bytes}; }

GLuint makeBuffer(size_t bytes, const void* data) {
    GLuint b = 0;
    glCreateBuffers(1, &b);
    glNamedBufferStorage(b, GLsizeiptr(bytes), data, GL_DYNAMIC_STORAGE_BIT);
    return b;
}

int failures = 0;
void check(bool ok, const char* what) {
    std::printf("%s: %s\n", ok ? "ok" : "FAILED", what);
    failures += !ok;
}

}  // namespace

int main() {
    if (!makeContext()) {
        std::printf("no EGL surfaceless GL 4.5 context here: skipped\n");
        return 77;
    }
    std::printf("GL %s on %s, loader libepoxy\n", glGetString(GL_VERSION), glGetString(GL_RENDERER));

    // 1. Scan.
    {
        std::mt19937 rng(7);
        std::vector<uint32_t> values(100003);
        for (auto& v : values) v = rng();
        std::vector<uint32_t> want(values.size()), got(values.size());
        penumbra::scanCpu(values.data(), want.data(), values.size(), penumbra::ScanKind::Exclusive);
        const GLuint in = makeBuffer(values.size() * 4, values.data()), out = makeBuffer(values.size() * 4, nullptr);
        penumbra::Scanner scanner;
        scanner.reserve(values.size());
        const penumbra::Status s = scanner.exclusive(range(in, values.size() * 4), range(out, values.size() * 4), values.size());
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        glGetNamedBufferSubData(out, 0, GLsizeiptr(got.size() * 4), got.data());
        check(s == penumbra::Status::Ok && got == want, "scan of 100003 uints == scanCpu");
        glDeleteBuffers(1, &in);
        glDeleteBuffers(1, &out);
    }

    // A ground quad and a floating triangle; view samples on the ground.
    const std::vector<glm::vec3> vertices = {{-2, 0, -2}, {2, 0, -2}, {2, 0, 2}, {-2, 0, 2},
                                             {-0.5f, 1, -0.4f}, {0.6f, 1, -0.2f}, {0.0f, 1.1f, 0.7f}};
    const std::vector<uint32_t> indices = {0, 2, 1, 0, 3, 2, 4, 5, 6};
    const int side = 64;
    std::vector<glm::vec4> positions, normals;
    for (int y = 0; y < side; ++y) {
        for (int x = 0; x < side; ++x) {
            positions.emplace_back(-1.9f + 3.8f * (x + 0.5f) / side, 0.0f, -1.9f + 3.8f * (y + 0.5f) / side, 1.0f);
            normals.emplace_back(0, 1, 0, 0);
        }
    }
    const uint32_t n = uint32_t(positions.size());
    const GLuint position_buffer = makeBuffer(n * 16, positions.data()), normal_buffer = makeBuffer(n * 16, normals.data());
    const penumbra::SampleBufferInput input{range(position_buffer, n * 16), range(normal_buffer, n * 16)};
    penumbra::SampleListsLight light;
    light.light = glm::vec4(0.3f, 4.0f, 0.2f, 1.0f);
    const auto [lo, hi] = penumbra::viewSampleBounds(positions.data(), positions.size());
    light.view_projection = penumbra::lightViewProjectionForBounds(light.light, lo, hi);

    // 2. Sample lists in buffers the consumer owns (one buffer, sub-ranges at aligned offsets).
    {
        const penumbra::SampleListsSetup setup = penumbra::sampleListsSetup(64, 64, n);
        penumbra::SampleListBuilder builder;
        builder.reserve(setup);
        const uint64_t a = builder.storageAlignment() < 256 ? 256 : builder.storageAlignment();
        const uint64_t sizes[] = {setup.counts_bytes,       setup.offsets_bytes,       setup.list_positions_bytes,
                                  setup.list_ids_bytes,     setup.sample_slots_bytes,  setup.sample_texels_bytes,
                                  setup.header_bytes,       sizeof(penumbra::SampleListsFrustum)};
        uint64_t offsets[8], total = 0;
        for (int i = 0; i < 8; ++i) {
            offsets[i] = total;
            total += (sizes[i] + a - 1) / a * a;
        }
        const GLuint arena = makeBuffer(total, nullptr);
        penumbra::SampleListsBuffers out;
        penumbra::BufferRange* fields[] = {&out.counts,       &out.offsets,       &out.list_positions, &out.list_ids,
                                           &out.sample_slots, &out.sample_texels, &out.header,         &out.frustum};
        for (int i = 0; i < 8; ++i) *fields[i] = {arena, offsets[i], sizes[i]};
        builder.validate(setup, input, out);
        penumbra::SampleListsBuild build;
        build.fit_frustum = true;
        const penumbra::Status s = builder.build(setup, light, input, out, {}, build);
        const penumbra::SampleListsFrustum frustum = penumbra::SampleListBuilder::readFrustum(out.frustum);
        penumbra::SampleListsLight fitted = light;
        fitted.view_projection = frustum.view_projection;
        const auto gpu = penumbra::downloadSampleLists(setup, out);
        const auto cpu = penumbra::buildSampleListsCpu(setup, fitted, positions.data(), normals.data());
        check(s == penumbra::Status::Ok && frustum.info.x == 1 && penumbra::sampleListsDifference(gpu, cpu).empty(),
              "sample lists in sub-ranges of one buffer, fitted on the GPU == CPU twin");
        glDeleteBuffers(1, &arena);
    }

    // 3. Hard shadows: the consumer's own VAO and index buffer, drawn in the callback.
    {
        penumbra::AliasFreeHardOptions options;
        options.grid_width = options.grid_height = 96;
        penumbra::AliasFreeHardShadows pipeline(options);
        pipeline.reserve(n);
        pipeline.validate(input, n);
        GLuint vao = 0;
        glCreateVertexArrays(1, &vao);
        const GLuint vbo = makeBuffer(vertices.size() * 12, vertices.data()), ibo = makeBuffer(indices.size() * 4, indices.data());
        glVertexArrayVertexBuffer(vao, 0, vbo, 0, 12);
        glVertexArrayElementBuffer(vao, ibo);
        glEnableVertexArrayAttrib(vao, 0);
        glVertexArrayAttribFormat(vao, 0, 3, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(vao, 0, 0);
        const auto draw = [&](penumbra::CasterClass cls) {
            if (cls != penumbra::CasterClass::Open) return;
            glBindVertexArray(vao);
            glDrawElements(GL_TRIANGLES, GLsizei(indices.size()), GL_UNSIGNED_INT, nullptr);
        };
        const penumbra::Status s = pipeline.run(input, n, light, draw);
        std::vector<uint32_t> states(n);
        glGetNamedBufferSubData(pipeline.states().buffer, 0, GLsizeiptr(n * 4), states.data());
        penumbra::reference::VisibilityOracle oracle(vertices, indices);
        penumbra::reference::VisibilityOptions oracle_options;
        oracle_options.coplanar_epsilon = options.coplanar_epsilon;
        size_t mismatched = 0, shadowed = 0, tested = 0;
        for (uint32_t id = 0; id < n; ++id) {
            if (states[id] != PENUMBRA_AFH_LIT && states[id] != PENUMBRA_AFH_SHADOWED) continue;
            ++tested;
            bool tie = false;
            const bool blocked = oracle.segmentBlocked(glm::dvec3(glm::vec3(positions[id])), glm::dvec3(glm::vec3(light.light)),
                                                       oracle_options, &tie);
            shadowed += states[id] == PENUMBRA_AFH_SHADOWED;
            if (!tie) mismatched += blocked != (states[id] == PENUMBRA_AFH_SHADOWED);
        }
        std::printf("hard shadows: %zu samples tested, %zu shadowed, %zu mismatched\n", tested, shadowed, mismatched);
        check(s == penumbra::Status::Ok && tested == n && shadowed > 100 && mismatched == 0,
              "hard shadows == the oracle on every sample");
        glDeleteVertexArrays(1, &vao);
        glDeleteBuffers(1, &vbo);
        glDeleteBuffers(1, &ibo);
    }
    glDeleteBuffers(1, &position_buffer);
    glDeleteBuffers(1, &normal_buffer);
    const GLenum error = glGetError();
    check(error == GL_NO_ERROR, "no GL error left behind");
    return failures == 0 ? 0 : 1;
}
