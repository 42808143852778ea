// A small scene for the GL tests that run whole blocks (frame_contract_test, engine_state_test):
// its 96 x 72 G-buffer, a point light whose frustum sees every view sample (the box padded for
// depth reconstruction, which moves samples by ~1e-5 relative), the sample inputs of both kinds,
// the caster callback the pipelines take and the caster buffers the stencil takes.
#ifndef PENUMBRA_TESTS_SUPPORT_GL_WORLD_HPP
#define PENUMBRA_TESTS_SUPPORT_GL_WORLD_HPP

#include "penumbra/buffer_range.hpp"
#include "penumbra/gl/objects.hpp"
#include "penumbra/gl/sample_lists.hpp"
#include "penumbra/gl/shadow_edge_stencil.hpp"
#include "penumbra/influence_region.hpp"
#include "penumbra/light_lut.hpp"
#include "penumbra/light_samples.hpp"
#include "penumbra/pipelines/caster_class.hpp"
#include "penumbra/sample_lists.hpp"
#include "penumbra/scene/gl_scene.hpp"
#include "penumbra/scene/scene.hpp"

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

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

/// The casters of a scene without its ground, merged: what the deep-shadow-map tests render.
struct SceneCasters {
    std::vector<glm::vec3> positions;
    std::vector<uint32_t> indices;
};

inline SceneCasters castersWithoutGround(const scene::Scene& scene) {
    scene::Mesh casters = scene.casters();
    return {std::move(casters.positions), std::move(casters.indices)};
}

/// The soft pipeline's light for a world: N samples (one set, seed 7) of the scene's spherical
/// light, their certified LUT (generated on the CPU, uploaded) and the influence regions over a
/// grid x grid light grid whose far plane lies beyond every corner of the world's padded box.
struct GlSoftLight {
    LightSampleSets sets;
    LightLutSetup lut;
    gl::Buffer lut_buffer;
    InfluenceRegionSetup influence;

    GlSoftLight(const GlWorld& w, uint32_t lut_resolution, uint32_t grid = 64, uint32_t n = 128) {
        const glm::mat4 vp = w.light.view_projection;
        double far_depth = 0.0;
        for (int corner = 0; corner < 8; ++corner) {
            const glm::vec3 x((corner & 1) ? w.hi.x : w.lo.x, (corner & 2) ? w.hi.y : w.lo.y, (corner & 4) ? w.hi.z : w.lo.z);
            far_depth = std::max(far_depth, double((vp * glm::vec4(x, 1.0f)).w));
        }
        Light light;
        light.center = glm::dvec3(w.scene.light.position);
        light.size = glm::dvec3(double(w.scene.light.radius));
        LightSampleOptions so;
        so.count = n;
        so.sets = 1;
        so.seed = 7;
        sets = makeLightSampleSets(light, so);
        LightLutOptions lut_options;
        lut_options.resolution = lut_resolution;
        lut_options.certified = true;
        lut = lightLutSetup(sets, lut_options);
        lut_buffer = gl::Buffer::fromVector(generateLightLut(lut));
        InfluenceRegionOptions io;
        io.grid_width = io.grid_height = grid;
        io.far_plane = influenceFarPlaneAtDepth(vp, far_depth * 1.01 + 1e-3);
        influence = influenceRegionSetup(light, vp, io);
    }
    BufferRange table() const { return {lut_buffer.id(), 0, lut_buffer.size()}; }
};

}  // namespace penumbra::test

#endif
