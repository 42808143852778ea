// The two soft-shadow baselines benchmarks/sample_based_soft_bench.cpp measures the sample-based
// pipeline (sintorn2008 §4) against, with their GLSL as string literals (they are benchmark code,
// not a penumbra block: no shader folder, no CPU twin).
//
//   AveragedShadowMaps  sintorn2008 §5, Fig. 13: the alternative that also yields per-light-sample
//                       visibility on arbitrary receivers, as many shadow maps as light samples
//                       (the seed: about 10x slower than its method, and aliased). One ordinary depth map per
//                       light sample (the same world samples the pipeline and the oracle use), each
//                       rendered with every caster from its own frustum, and per view sample one
//                       nearest-texel depth compare per map: bit s of the sample's mask = light
//                       sample s blocked, visibility = 1 - popcount / N. Maps are rendered L at a
//                       time into the layers of one GL_TEXTURE_2D_ARRAY, then one compute pass
//                       writes the L bits of that batch per view sample, so the maps cost N depth
//                       renders + N / L lookup passes. L = 32 (one whole mask word per pass, no
//                       read-modify-write) while 32 maps fit in kMapBatchBytes (2 GiB: map sizes
//                       up to 4096^2); larger maps take L = the power of two that fits (8 at
//                       8192^2), and each pass ORs its bits into the word (each word is owned
//                       by one invocation; a barrier orders the passes).
//   Pcss                percentage-closer soft shadows (Fernando 2005), the usual real-time
//                       approximation: one depth map from the light's centre; per view sample a
//                       blocker search over the map region from which blockers between the sample
//                       and the light's disk can be seen, the average blocker depth, the penumbra
//                       width by similar triangles, then PCF over that width. No per-light-sample
//                       bits: only its visible fraction is compared with the oracle's.
//
// Frusta (baselineFrustum): perspective from the map's eye, its cone holding the receivers' box
// (the view samples' bounds: every segment from the eye to a receiver lies inside, so every caster
// that can block one is rasterised), near = half the nearest box corner's depth for the depth
// precision of a GL_DEPTH_COMPONENT32F map (casters nearer than that are clamped by
// GL_DEPTH_CLAMP and still cast), far beyond the farthest corner.
// Bias: glPolygonOffset(2, 4) when a map is rendered (slope factor 2, 4 units: the typical
// slope-scaled bias; benchmarks/alias_free_hard_bench.cpp uses the same), plain `>` in the lookup.
//
// GL state after run(): framebuffer 0 bound, GL_DEPTH_TEST, GL_DEPTH_CLAMP and
// GL_POLYGON_OFFSET_FILL off, the viewport the map's, the programs / SSBO bindings 0-2 /
// texture unit 0 / storage bindings left as the run set them.
#ifndef PENUMBRA_BENCHMARKS_SOFT_BASELINES_HPP
#define PENUMBRA_BENCHMARKS_SOFT_BASELINES_HPP

#include <penumbra/detail/dispatch.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/shader.hpp>
#include <penumbra/pipelines/sample_based_soft.hpp>
#include <penumbra/sample_lists.hpp>
#include <penumbra/scene/gl_scene.hpp>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace penumbra::bench {

// glPolygonOffset(factor, units) of every baseline depth map.
inline constexpr float kBaselineSlopeBias = 2.0f;
inline constexpr float kBaselineConstantBias = 4.0f;
// Maps per GL_TEXTURE_2D_ARRAY batch: at most one 32-bit mask word per view sample and batch, and
// at most kMapBatchBytes of depth texels.
inline constexpr uint32_t kMapsPerBatch = 32;
inline constexpr uint64_t kMapBatchBytes = 2ull << 30;

/// Layers per batch for maps of size^2 float depths: a power of two in [1, 32] (it divides 32, so
/// a batch never straddles two mask words).
inline uint32_t mapsPerBatch(uint32_t size) {
    uint32_t layers = kMapsPerBatch;
    while (layers > 1 && uint64_t(layers) * size * size * 4 > kMapBatchBytes) layers /= 2;
    return layers;
}

/// A light frustum for a baseline depth map (see the file comment).
struct BaselineFrustum {
    glm::mat4 view{1.0f}, projection{1.0f}, view_projection{1.0f};
    glm::mat4 light_texture{1.0f};  ///< lightTextureMatrix(view_projection): x, y, z in [0, w] inside
    float near_plane = 0.0f, far_plane = 0.0f;
};

inline BaselineFrustum baselineFrustum(const glm::vec3& eye, const glm::vec3& lo, const glm::vec3& hi) {
    // The cone's axis: the mean of the unit vectors to the corners (as lightViewProjectionForBounds).
    glm::vec3 axis(0.0f);
    for (int k = 0; k < 8; ++k) {
        const glm::vec3 corner((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z);
        const glm::vec3 v = corner - eye;
        if (glm::length(v) > 0.0f) axis += glm::normalize(v);
    }
    PENUMBRA_CHECK(glm::length(axis) > 1e-6f, "soft_baselines: the eye is at the receivers' box centre");
    const glm::vec3 dir = glm::normalize(axis);
    float max_tan = 0.0f, min_depth = 1e30f, max_depth = 0.0f;
    for (int k = 0; k < 8; ++k) {
        const glm::vec3 corner((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z);
        const glm::vec3 v = corner - eye;
        const float depth = glm::dot(v, dir);
        PENUMBRA_CHECK(depth > 0.0f, "soft_baselines: a receiver-box corner lies behind the map's eye");
        max_tan = std::max(max_tan, glm::length(v - depth * dir) / depth);
        min_depth = std::min(min_depth, depth);
        max_depth = std::max(max_depth, depth);
    }
    BaselineFrustum f;
    f.near_plane = std::max(0.5f * min_depth, 1e-3f * max_depth);
    f.far_plane = 1.01f * max_depth;
    const glm::vec3 up = std::abs(dir.y) > 0.99f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    f.view = glm::lookAt(eye, eye + dir, up);
    f.projection = glm::perspective(2.0f * std::atan(1.01f * max_tan), 1.0f, f.near_plane, f.far_plane);
    f.view_projection = f.projection * f.view;
    f.light_texture = lightTextureMatrix(f.view_projection, LightDepthRange::MinusOneToOne);
    return f;
}

namespace detail {

/// Render state shared by both baselines' depth passes.
inline void beginDepthMaps(uint32_t size) {
    glViewport(0, 0, GLsizei(size), GLsizei(size));
    glDepthMask(GL_TRUE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);
    glDisable(GL_RASTERIZER_DISCARD);
    glEnable(GL_DEPTH_CLAMP);  // casters in front of the near plane still cast
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(kBaselineSlopeBias, kBaselineConstantBias);
}

inline void endDepthMaps() {
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_DEPTH_CLAMP);
    glDisable(GL_DEPTH_TEST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

inline const ShaderLibrary& baselineShaders() {
    static const ShaderLibrary library = [] {
        ShaderLibrary lib = ShaderLibrary::embedded();
        // One batch of averaged shadow maps: bit (first % 32) + l of word first / 32 = light sample
        // first + l blocked (nearest texel, `>`: the map's bias is its polygon offset); a batch
        // that starts a word writes it, the others OR into it.
        lib.add("bench/soft/maps_accumulate.comp.glsl", R"(
#include "penumbra/common/dispatch.glsl"
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = 1) buffer Masks { uint masks[]; };
layout(std430, binding = 2) readonly buffer LightTextures { mat4 light_textures[]; };
layout(binding = 0) uniform sampler2DArray maps;
layout(location = 0) uniform uint sample_count;
layout(location = 1) uniform uint first;
layout(location = 2) uniform uint words;
layout(location = 3) uniform uint layers;

void main() {
    const uint id = penumbraLinearGroup() * 256u + gl_LocalInvocationID.x;
    if (id >= sample_count) return;
    const vec4 p = positions[id];
    uint mask = 0u;
    if (p.w != 0.0) {
        const ivec2 size = textureSize(maps, 0).xy;
        for (uint l = 0u; l < layers; ++l) {
            const vec4 t = light_textures[first + l] * vec4(p.xyz, 1.0);
            const vec3 q = t.xyz / t.w;
            // Every receiver lies inside every map's frustum (baselineFrustum); NaN stays lit.
            if (!(t.w > 0.0) || !(q.x >= 0.0 && q.x <= 1.0 && q.y >= 0.0 && q.y <= 1.0)) continue;
            const ivec2 texel = min(ivec2(q.xy * vec2(size)), size - 1);
            if (min(q.z, 1.0) > texelFetch(maps, ivec3(texel, int(l)), 0).r) mask |= 1u << l;
        }
    }
    const uint word = id * words + first / 32u, shift = first % 32u;
    masks[word] = shift == 0u ? mask : masks[word] | (mask << shift);
}
)");
        // Visible fraction of each view sample from its mask (as the pipeline's resolve).
        lib.add("bench/soft/maps_resolve.comp.glsl", R"(
#include "penumbra/common/dispatch.glsl"
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = 1) readonly buffer Masks { uint masks[]; };
layout(std430, binding = 2) writeonly buffer Visibility { float visibility[]; };
layout(location = 0) uniform uint sample_count;
layout(location = 2) uniform uint words;
layout(location = 4) uniform uint light_samples;

void main() {
    const uint id = penumbraLinearGroup() * 256u + gl_LocalInvocationID.x;
    if (id >= sample_count) return;
    if (positions[id].w == 0.0) {
        visibility[id] = -1.0;
        return;
    }
    uint blocked = 0u;
    for (uint w = 0u; w < words; ++w) blocked += uint(bitCount(masks[id * words + w]));
    visibility[id] = 1.0 - float(blocked) / float(light_samples);
}
)");
        // PCSS (Fernando 2005) from one map at the light's centre. Depths along the light's view
        // axis; "tangent units" = offset / depth, uv = 0.5 * P00 * tangent (the map's frustum is
        // square and symmetric). Blockers between the receiver (depth zr) and a light of radius r
        // can be seen from the centre within r (zr - z) / (z zr) tangent units, largest at the
        // near plane; a blocker at depth zb casts a penumbra of half-width r (zr - zb) / zb around
        // the receiver, r (zr - zb) / (zb zr) tangent units from the centre. Both radii are
        // capped at 0.25 of the map. Taps: a Vogel (golden-angle) disk, the same for every sample.
        lib.add("bench/soft/pcss.comp.glsl", R"(
#include "penumbra/common/dispatch.glsl"
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = 1) writeonly buffer Visibility { float visibility[]; };
layout(binding = 0) uniform sampler2D depth_map;
layout(location = 0) uniform mat4 light_texture;
layout(location = 1) uniform mat4 light_view;
layout(location = 2) uniform uint sample_count;
layout(location = 3) uniform vec4 lens;  // uv per tangent unit, light radius, near, far
layout(location = 4) uniform uvec2 taps;  // blocker-search taps, filter taps

vec2 vogel(uint i, uint n) {
    const float radius = sqrt((float(i) + 0.5) / float(n));
    const float angle = float(i) * 2.39996323;
    return radius * vec2(cos(angle), sin(angle));
}

float mapDepth(vec2 uv, ivec2 size) {
    const ivec2 texel = clamp(ivec2(uv * vec2(size)), ivec2(0), size - 1);
    return texelFetch(depth_map, texel, 0).r;
}

float linearDepth(float d) {  // window depth [0, 1] of glm::perspective (NDC z in [-1, 1])
    return lens.z * lens.w / (lens.w - d * (lens.w - lens.z));
}

void main() {
    const uint id = penumbraLinearGroup() * 256u + gl_LocalInvocationID.x;
    if (id >= sample_count) return;
    const vec4 p = positions[id];
    if (p.w == 0.0) {
        visibility[id] = -1.0;
        return;
    }
    const vec4 t = light_texture * vec4(p.xyz, 1.0);
    const vec3 q = t.xyz / t.w;
    if (!(t.w > 0.0) || !(q.x >= 0.0 && q.x <= 1.0 && q.y >= 0.0 && q.y <= 1.0)) {
        visibility[id] = 1.0;
        return;
    }
    const ivec2 size = textureSize(depth_map, 0);
    const float receiver = min(q.z, 1.0);
    const float zr = -(light_view * vec4(p.xyz, 1.0)).z;
    const float search = min(lens.x * lens.y * max(zr - lens.z, 0.0) / (zr * lens.z), 0.25);
    float blocker_sum = 0.0;
    uint blockers = 0u;
    for (uint i = 0u; i < taps.x; ++i) {
        const float d = mapDepth(q.xy + search * vogel(i, taps.x), size);
        if (receiver > d) {
            blocker_sum += linearDepth(d);
            ++blockers;
        }
    }
    if (blockers == 0u) {
        visibility[id] = 1.0;
        return;
    }
    const float zb = blocker_sum / float(blockers);
    const float filter_radius = min(lens.x * lens.y * max(zr - zb, 0.0) / (zb * zr), 0.25);
    uint lit = 0u;
    for (uint i = 0u; i < taps.y; ++i) lit += receiver > mapDepth(q.xy + filter_radius * vogel(i, taps.y), size) ? 0u : 1u;
    visibility[id] = float(lit) / float(taps.y);
}
)");
        return lib;
    }();
    return library;
}

}  // namespace detail

/// sintorn2008 §5's alternative: one shadow map per light sample, averaged (see the file comment).
class AveragedShadowMaps {
public:
    /// `positions`: vec4 per view-sample id (w == 0: none); `light_samples`: world positions;
    /// [lo, hi]: the receivers' box; maps of map_size^2 texels.
    AveragedShadowMaps(const scene::GpuScene& casters, const gl::Buffer& positions, uint32_t sample_count,
                       const std::vector<glm::dvec3>& light_samples, const glm::vec3& lo, const glm::vec3& hi,
                       uint32_t map_size)
        : casters_(casters), positions_(positions), count_(sample_count), n_(uint32_t(light_samples.size())),
          words_((n_ + 31) / 32), size_(map_size), per_batch_(mapsPerBatch(map_size)), maps_(GL_TEXTURE_2D_ARRAY),
          masks_(size_t(std::max(sample_count, 1u)) * words_ * 4), visibility_(size_t(std::max(sample_count, 1u)) * 4) {
        PENUMBRA_CHECK(n_ > 0, "AveragedShadowMaps: no light samples");
        std::vector<glm::mat4> light_textures(size_t(words_) * kMapsPerBatch, glm::mat4(1.0f));
        for (uint32_t s = 0; s < n_; ++s) {
            const BaselineFrustum f = baselineFrustum(glm::vec3(light_samples[s]), lo, hi);
            view_projections_.push_back(f.view_projection);
            light_textures[s] = f.light_texture;
        }
        light_textures_ = gl::Buffer::fromVector(light_textures);
        glTextureStorage3D(maps_.id(), 1, GL_DEPTH_COMPONENT32F, GLsizei(size_), GLsizei(size_), GLsizei(per_batch_));
        glTextureParameteri(maps_.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTextureParameteri(maps_.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTextureParameteri(maps_.id(), GL_TEXTURE_COMPARE_MODE, GL_NONE);
        for (uint32_t l = 0; l < per_batch_; ++l) {
            framebuffers_.push_back(gl::Framebuffer::create());
            const GLuint fbo = framebuffers_.back().id();
            glNamedFramebufferTextureLayer(fbo, GL_DEPTH_ATTACHMENT, maps_.id(), 0, GLint(l));
            glNamedFramebufferDrawBuffer(fbo, GL_NONE);
            glNamedFramebufferReadBuffer(fbo, GL_NONE);
            PENUMBRA_CHECK(glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE,
                           "AveragedShadowMaps: framebuffer incomplete");
        }
        depth_ = gl::buildProgram({"penumbra/scene/depth_only.vert.glsl"});
        accumulate_ = gl::buildComputeProgram("bench/soft/maps_accumulate.comp.glsl", {}, detail::baselineShaders());
        resolve_ = gl::buildComputeProgram("bench/soft/maps_resolve.comp.glsl", {}, detail::baselineShaders());
        grid_ = penumbra::detail::foldDispatch(penumbra::detail::divUp(count_, 256));
        gl::checkErrors("AveragedShadowMaps setup");
    }

    /// Every map, every lookup and the resolve (the timed region).
    void run() const {
        for (uint32_t first = 0; first < n_; first += per_batch_) {
            const uint32_t layers = std::min(per_batch_, n_ - first);
            detail::beginDepthMaps(size_);
            depth_.use();
            const float far_depth = 1.0f;
            for (uint32_t l = 0; l < layers; ++l) {
                const GLuint fbo = framebuffers_[l].id();
                glBindFramebuffer(GL_FRAMEBUFFER, fbo);
                glClearNamedFramebufferfv(fbo, GL_DEPTH, 0, &far_depth);
                glUniformMatrix4fv(0, 1, GL_FALSE, glm::value_ptr(view_projections_[first + l]));
                casters_.draw();
            }
            detail::endDepthMaps();
            // Framebuffer writes are visible to later texture fetches, and these fetches finish
            // before the next batch's renders: no barrier needed around the maps.
            accumulate_.use();
            glUniform1ui(0, count_);
            glUniform1ui(1, first);
            glUniform1ui(2, words_);
            glUniform1ui(3, layers);
            glBindTextureUnit(0, maps_.id());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, positions_.id());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, masks_.id());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, light_textures_.id());
            if (grid_.groups) glDispatchCompute(grid_.x, grid_.y, 1);
            // The next pass may OR into the words this one wrote (per_batch_ < 32).
            if (per_batch_ < kMapsPerBatch) glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        }
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        resolve_.use();
        glUniform1ui(0, count_);
        glUniform1ui(2, words_);
        glUniform1ui(4, n_);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, positions_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, masks_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, visibility_.id());
        if (grid_.groups) glDispatchCompute(grid_.x, grid_.y, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    }

    std::vector<uint32_t> readMasks() const { return masks_.download<uint32_t>(0, size_t(count_) * words_); }
    std::vector<float> readVisibility() const { return visibility_.download<float>(0, count_); }
    uint32_t words() const { return words_; }
    uint32_t mapSize() const { return size_; }
    uint32_t batchLayers() const { return per_batch_; }

private:
    const scene::GpuScene& casters_;
    const gl::Buffer& positions_;
    uint32_t count_, n_, words_, size_, per_batch_;
    gl::Texture maps_;
    std::vector<gl::Framebuffer> framebuffers_;
    std::vector<glm::mat4> view_projections_;
    gl::Buffer light_textures_, masks_, visibility_;
    gl::Program depth_, accumulate_, resolve_;
    penumbra::detail::DispatchGrid grid_;
};

/// Percentage-closer soft shadows from one map at the light's centre (see the file comment).
class Pcss {
public:
    Pcss(const scene::GpuScene& casters, const gl::Buffer& positions, uint32_t sample_count, const glm::vec3& light_center,
         float light_radius, const glm::vec3& lo, const glm::vec3& hi, uint32_t map_size, uint32_t blocker_taps,
         uint32_t filter_taps)
        : casters_(casters), positions_(positions), count_(sample_count), size_(map_size), radius_(light_radius),
          blocker_taps_(blocker_taps), filter_taps_(filter_taps), map_(GL_TEXTURE_2D),
          fbo_(gl::Framebuffer::create()), visibility_(size_t(std::max(sample_count, 1u)) * 4) {
        frustum_ = baselineFrustum(light_center, lo, hi);
        glTextureStorage2D(map_.id(), 1, GL_DEPTH_COMPONENT32F, GLsizei(size_), GLsizei(size_));
        glTextureParameteri(map_.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTextureParameteri(map_.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTextureParameteri(map_.id(), GL_TEXTURE_COMPARE_MODE, GL_NONE);
        glNamedFramebufferTexture(fbo_.id(), GL_DEPTH_ATTACHMENT, map_.id(), 0);
        glNamedFramebufferDrawBuffer(fbo_.id(), GL_NONE);
        glNamedFramebufferReadBuffer(fbo_.id(), GL_NONE);
        PENUMBRA_CHECK(glCheckNamedFramebufferStatus(fbo_.id(), GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE,
                       "Pcss: framebuffer incomplete");
        depth_ = gl::buildProgram({"penumbra/scene/depth_only.vert.glsl"});
        pcss_ = gl::buildComputeProgram("bench/soft/pcss.comp.glsl", {}, detail::baselineShaders());
        grid_ = penumbra::detail::foldDispatch(penumbra::detail::divUp(count_, 256));
        gl::checkErrors("Pcss setup");
    }

    void run() const {
        detail::beginDepthMaps(size_);
        depth_.use();
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_.id());
        const float far_depth = 1.0f;
        glClearNamedFramebufferfv(fbo_.id(), GL_DEPTH, 0, &far_depth);
        glUniformMatrix4fv(0, 1, GL_FALSE, glm::value_ptr(frustum_.view_projection));
        casters_.draw();
        detail::endDepthMaps();
        pcss_.use();
        glUniformMatrix4fv(0, 1, GL_FALSE, glm::value_ptr(frustum_.light_texture));
        glUniformMatrix4fv(1, 1, GL_FALSE, glm::value_ptr(frustum_.view));
        glUniform1ui(2, count_);
        glUniform4f(3, 0.5f * frustum_.projection[0][0], radius_, frustum_.near_plane, frustum_.far_plane);
        glUniform2ui(4, blocker_taps_, filter_taps_);
        glBindTextureUnit(0, map_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, positions_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, visibility_.id());
        if (grid_.groups) glDispatchCompute(grid_.x, grid_.y, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    }

    std::vector<float> readVisibility() const { return visibility_.download<float>(0, count_); }
    uint32_t mapSize() const { return size_; }

private:
    const scene::GpuScene& casters_;
    const gl::Buffer& positions_;
    uint32_t count_, size_;
    float radius_;
    uint32_t blocker_taps_, filter_taps_;
    gl::Texture map_;
    gl::Framebuffer fbo_;
    gl::Buffer visibility_;
    gl::Program depth_, pcss_;
    BaselineFrustum frustum_;
    penumbra::detail::DispatchGrid grid_;
};

}  // namespace penumbra::bench

#endif
