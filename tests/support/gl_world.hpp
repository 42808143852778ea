// A small scene for the GL tests that run whole blocks (frame_contract_test, engine_state_test):
// its 96 x 72 G-buffer, a point light whose frustum sees every view sample (the box padded for
// depth reconstruction, which moves samples by ~1e-5 relative), the sample inputs of both kinds,
// the caster callback the pipelines take and the caster buffers the stencil takes.
#ifndef PENUMBRA_TESTS_SUPPORT_GL_WORLD_HPP
#define PENUMBRA_TESTS_SUPPORT_GL_WORLD_HPP

#include "penumbra/buffer_range.hpp"
#include "penumbra/gl/sample_lists.hpp"
#include "penumbra/gl/shadow_edge_stencil.hpp"
#include "penumbra/pipelines/caster_class.hpp"
#include "penumbra/sample_lists.hpp"
#include "penumbra/scene/gl_scene.hpp"
#include "penumbra/scene/scene.hpp"

#include <utility>

namespace penumbra::test {

struct GlWorld {
    static constexpr uint32_t kWidth = 96, kHeight = 72;
    scene::Scene scene;
    scene::GpuScene gpu;
    scene::GBuffer gbuffer{kWidth, kHeight};
    glm::mat4 camera{1.0f};
    glm::vec3 lo{0.0f}, hi{0.0f};  ///< the view samples' box, padded
    SampleListsLight light;
    SampleListsView view;

    explicit GlWorld(scene::Scene s = scene::builtin("torus_knot")) : scene(std::move(s)), gpu(scene) {
        camera = scene.camera.projection(float(kWidth) / float(kHeight)) * scene.camera.view();
        gbuffer.render(gpu, camera);
        const auto positions = gbuffer.positionBuffer().download<glm::vec4>();
        const auto bounds = viewSampleBounds(positions.data(), positions.size());
        const glm::vec3 pad = 0.01f * (bounds.second - bounds.first) + glm::vec3(1e-3f);
        lo = bounds.first - pad;
        hi = bounds.second + pad;
        light.light = glm::vec4(scene.light.position, 1.0f);
        light.view_projection = lightViewProjectionForBounds(light.light, lo, hi);
        view.width = kWidth;
        view.height = kHeight;
        view.inverse_view_projection = glm::inverse(camera);
    }
    uint32_t samples() const { return kWidth * kHeight; }
    static BufferRange whole(const gl::Buffer& b) { return {b.id(), 0, b.size()}; }
    SampleBufferInput bufferInput() const { return {whole(gbuffer.positionBuffer()), whole(gbuffer.faceBuffer())}; }
    SampleDepthInput depthInput() const { return {gbuffer.depthTexture(), gbuffer.faceTexture(), view}; }
    /// The pipelines' caster callback: every mesh of the class.
    void drawClass(CasterClass cls) const { gpu.drawClass(cls == CasterClass::Closed); }
    /// Every triangle for the stencil (GpuScene interleaves position and normal: 24 bytes a vertex).
    gl::AaCasterBuffers aaCasters() const {
        gl::AaCasterBuffers c;
        c.stride = 24;
        c.index_count = gpu.indexCount();
        c.positions = {gpu.vertexBuffer(), 0, 24ull * gpu.positions().size()};
        c.indices = {gpu.indexBuffer(), 0, 4ull * c.index_count};
        return c;
    }
};

}  // namespace penumbra::test

#endif
