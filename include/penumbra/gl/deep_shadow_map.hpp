// penumbra — deep shadow maps on the GPU (lokovic2000 §3-§5): the GL executor. The rules, the setup
// and the CPU twin are penumbra/deep_shadow_map.hpp; this header runs them.
//
// Integration summary
//   needs:    GL 4.5 (geometry shaders for the conservative emitter); PENUMBRA_GL_HEADER; a scan
//             block (the builder owns one Scanner); casters as a vec3 float vertex buffer range +
//             uint32 index range (GL_TRIANGLES); optional per-vertex opacity (vec3 float range),
//             per-triangle opacity (vec4 float range) or the opacity hook (a vec3 float attribute
//             range, e.g. texture coordinates, handed to penumbraDsmOpacityHook in
//             penumbra/deep_shadow_map/opacity_hook.glsl: replace that file in your ShaderLibrary
//             for your material, or bind an opacity texture for the default one).
//   produces: the map in the builder's buffers (offsets(), vertices(): the layout of lookup.glsl —
//             float z per vertex, then from word `capacity.vertices` on the 16-bit V values),
//             plus a status block (PENUMBRA_DSM_STATUS_*: fragments dropped over the capacity,
//             vertices dropped, ...) the integrator may read after the frame (readStatus()).
//   passes:   1 raster count (conservative hull per triangle, each fragment tests its texel's S
//             sub-samples; atomicAdd per sub-sample list), 2 exclusive scan of the R*R*S + 1
//             counts (the scan block), 3 raster scatter (offset + atomic cursor), 4 sort every list
//             by (depth, triangle) — from here on the order is deterministic —, 5 merge + compress
//             count per texel, scan, merge + compress write, 6 per mip level: average + compress
//             count, scan, write. All decisions stay on the GPU.
//   state:    build() binds its programs, its vertex array, its attachment-less framebuffer, the
//             viewport R x R, uniform bindings 0-1, storage bindings 0-7 and, with an opacity
//             texture, texture unit PENUMBRA_DSM_OPACITY_TEXTURE_UNIT (0), disables depth
//             test, culling and rasterizer discard and sets gl::setPassRasterState's rasterizer
//             state (scissor off, polygon fill, clip distances off, clip control lower-left /
//             -1..1, no primitive restart, ...); it restores none of these (the integrator
//             rebinds what it uses next). It never queries GL state, never reads back and never
//             allocates: everything is sized at construction from the capacities.
//   limits:   llvmpipe stops an invocation's loops after 65 535 iterations in total; the merge of a
//             texel performs ~(fragments in its lists) x log2(lists) heap steps, so keep
//             S x depth complexity x 8 well below that on llvmpipe (S <= 64 in the tests).
#ifndef PENUMBRA_GL_DEEP_SHADOW_MAP_HPP
#define PENUMBRA_GL_DEEP_SHADOW_MAP_HPP

#include "penumbra/buffer_range.hpp"
#include "penumbra/conservative_raster.hpp"
#include "penumbra/deep_shadow_map.hpp"
#include "penumbra/detail/dispatch.hpp"
#include "penumbra/gl/gl.hpp"
#include "penumbra/gl/objects.hpp"
#include "penumbra/gl/scan.hpp"
#include "penumbra/gl/shader.hpp"
#include "penumbra/gl/validate.hpp"

#include <array>
#include <string>
#include <vector>

namespace penumbra::gl {

/// What one build() may produce at most (fixed at construction: the per-frame call never allocates).
struct DsmCapacity {
    uint64_t fragments = 1u << 22;  ///< caster fragments (sub-sample, triangle) over the whole map
    uint64_t vertices = 1u << 22;   ///< compressed vertices over every level
};

/// The casters of one build.
struct DsmCasterBuffers {
    BufferRange positions;          ///< vec3 float per vertex, tightly packed
    BufferRange indices;            ///< uint32, 3 per triangle
    uint32_t index_count = 0;
    BufferRange vertex_opacity;     ///< optional: vec3 float per vertex (PENUMBRA_DSM_OPACITY_VERTEX)
    BufferRange triangle_opacity;   ///< optional: vec4 float per triangle (PENUMBRA_DSM_OPACITY_TRIANGLE)
    /// The opacity hook (PENUMBRA_DSM_OPACITY_HOOK; wins over the others): penumbraDsmOpacityHook
    /// (opacity_hook.glsl, the builder's ShaderLibrary) gives the opacity of every covered
    /// sub-sample from the triangle's index within the draw and hook_attribute interpolated like
    /// the depth; the result is clamped to [0, 1] per channel, NaN -> 0. CPU twin: DsmOpacity::hook.
    bool opacity_hook = false;
    BufferRange hook_attribute;     ///< with opacity_hook: vec3 float per vertex (required)
    /// With opacity_hook: a 2D texture build() binds to unit PENUMBRA_DSM_OPACITY_TEXTURE_UNIT for
    /// the default hook (texelFetch at uv = attribute.xy, repeat, nearest); 0 leaves the unit alone
    /// (a replaced hook reading its own textures).
    GLuint opacity_texture = 0;
};

/// GPU time of the build's stages (enableStageTimers(): GL_TIME_ELAPSED queries; stageTimes() reads
/// them back: for tools and benchmarks, not for the frame), milliseconds.
struct DsmStageTimes {
    double rasterize = 0, sort = 0, merge_compress = 0, mips = 0;
    double total() const { return rasterize + sort + merge_compress + mips; }
};

/// Status words after a build (readStatus(): a read-back, for tests and tools, not for the frame).
struct DsmStatus {
    uint32_t fragments = 0, fragment_overflow = 0, vertices = 0, vertex_overflow = 0;
};

class DeepShadowMapBuilder {
public:
    DeepShadowMapBuilder(const DsmSetup& setup, const DsmCapacity& capacity = {},
                         const ShaderLibrary& library = ShaderLibrary::embedded())
        : setup_(setup), capacity_(capacity), scanner_(ScanOptions{}, library) {
        const uint64_t lists = uint64_t(setup.resolution) * setup.resolution * setup.samples;
        PENUMBRA_CHECK(lists + 1 <= 0xFFFFFFFFull, "DeepShadowMapBuilder: ", lists, " sub-sample lists exceed 2^32");
        PENUMBRA_CHECK(capacity.fragments >= 1 && capacity.fragments <= 0xFFFFFFFFull,
                       "DeepShadowMapBuilder: fragment capacity ", capacity.fragments, " is outside [1, 2^32)");
        PENUMBRA_CHECK(capacity.vertices >= 1 && capacity.vertices <= 0xFFFFFFFFull,
                       "DeepShadowMapBuilder: vertex capacity ", capacity.vertices, " is outside [1, 2^32)");
        lists_ = static_cast<uint32_t>(lists);
        const uint32_t stride = setup.channels == 3 ? 32u : 16u;
        for (uint32_t l = 0; l < setup.levels; ++l) {
            const uint32_t r = setup.level_resolution[l];
            offset_words_ += uint64_t(r) * r + 1;
        }
        ConservativeRasterOptions cr;
        cr.viewport_width = cr.viewport_height = static_cast<int>(setup.resolution);
        cr.variant = ConservativeVariant::Exact;
        cr.near_plane = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);  // only w >= min_w: nothing in front of the light is lost
        conservative_ = conservativeRasterSetup(cr);

        // Buffers (the per-frame path only clears and writes them).
        std::vector<glm::vec2> patterns = setup.pattern_offsets;
        for (float w : setup.gauss_table) patterns.emplace_back(w, 0.0f);
        patterns_ = Buffer::fromVector(patterns);
        counts_ = Buffer(4 * (lists + 1));
        cursor_ = Buffer(4 * lists);
        records_ = Buffer(stride * capacity.fragments);
        status_ = Buffer(4 * PENUMBRA_DSM_STATUS_WORDS);
        offsets_ = Buffer(4 * offset_words_);
        vertices_ = Buffer(4ull * (capacity.vertices + (capacity.vertices * setup.channels + 1) / 2));
        dummy_ = Buffer(16);
        ubo_stride_ = static_cast<uint32_t>((sizeof(DsmParams) + 255) / 256 * 256);
        params_ = Buffer(ubo_stride_ * (setup.levels + 1), nullptr, GL_DYNAMIC_STORAGE_BIT);
        conservative_ubo_ = Buffer(sizeof(ConservativeRasterParams), &conservative_.params, GL_DYNAMIC_STORAGE_BIT);
        scanner_.reserve(std::max<uint64_t>(lists + 1, uint64_t(setup.resolution) * setup.resolution + 1));
        staging_.resize(setup.levels + 1);

        // Programs.
        const std::string ch = std::to_string(setup.channels);
        ShaderDefines raster = conservative_.defines;
        raster.push_back({"PENUMBRA_DSM_CHANNELS", ch});
        ShaderDefines count = raster, scatter = raster;
        count.push_back({"PENUMBRA_DSM_PASS", "0"});
        scatter.push_back({"PENUMBRA_DSM_PASS", "1"});
        const std::vector<std::string> keys = {"penumbra/deep_shadow_map/raster.vert.glsl",
                                               "penumbra/deep_shadow_map/raster.geom.glsl",
                                               "penumbra/deep_shadow_map/raster.frag.glsl"};
        raster_count_ = buildProgram(keys, count, library);
        raster_scatter_ = buildProgram(keys, scatter, library);
        sort_ = buildComputeProgram("penumbra/deep_shadow_map/sort.comp.glsl", {{"PENUMBRA_DSM_CHANNELS", ch}}, library);
        for (int pass = 0; pass < 2; ++pass) {
            const ShaderDefines d = {{"PENUMBRA_DSM_CHANNELS", ch},
                                     {"PENUMBRA_DSM_PASS", std::to_string(pass)},
                                     {"PENUMBRA_DSM_MERGE_LISTS", std::to_string(setup.merge_lists)}};
            merge_[pass] = buildComputeProgram("penumbra/deep_shadow_map/merge.comp.glsl", d, library);
            mip_[pass] = buildComputeProgram("penumbra/deep_shadow_map/mip.comp.glsl",
                                             {{"PENUMBRA_DSM_CHANNELS", ch}, {"PENUMBRA_DSM_PASS", std::to_string(pass)}},
                                             library);
        }
        lookup_ = buildComputeProgram("penumbra/deep_shadow_map/lookup.comp.glsl", {{"PENUMBRA_DSM_CHANNELS", ch}}, library);

        glCreateVertexArrays(1, &vao_);
        glEnableVertexArrayAttrib(vao_, 0);
        glVertexArrayAttribFormat(vao_, 0, 3, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(vao_, 0, 0);
        glVertexArrayAttribFormat(vao_, 1, 3, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(vao_, 1, 1);
        glCreateFramebuffers(1, &fbo_);
        glNamedFramebufferParameteri(fbo_, GL_FRAMEBUFFER_DEFAULT_WIDTH, static_cast<GLint>(setup.resolution));
        glNamedFramebufferParameteri(fbo_, GL_FRAMEBUFFER_DEFAULT_HEIGHT, static_cast<GLint>(setup.resolution));
    }
    DeepShadowMapBuilder(const DeepShadowMapBuilder&) = delete;
    DeepShadowMapBuilder& operator=(const DeepShadowMapBuilder&) = delete;
    ~DeepShadowMapBuilder() {
        if (vao_) glDeleteVertexArrays(1, &vao_);
        if (fbo_) glDeleteFramebuffers(1, &fbo_);
    }

    /// Load time: makes build() bracket its four stages (rasterize = count + scan + scatter, sort,
    /// merge + compress, mips) with GL_TIME_ELAPSED queries, or, with wall_clock (drivers whose
    /// queries do not measure durations, e.g. llvmpipe), with glFinish + the wall clock — which
    /// synchronises the frame: a tool's setting, never an engine's.
    void enableStageTimers(bool wall_clock = false) { timers_.enable(wall_clock); }
    /// Read-back of the last build's stage times (waits for the GPU).
    DsmStageTimes stageTimes() const {
        DsmStageTimes t;
        t.rasterize = timers_.milliseconds(0);
        t.sort = timers_.milliseconds(1);
        t.merge_compress = timers_.milliseconds(2);
        t.mips = timers_.milliseconds(3);
        return t;
    }

    const DsmSetup& setup() const { return setup_; }
    BufferRange offsets() const { return {offsets_.id(), 0, 4 * offset_words_}; }
    BufferRange vertices() const { return {vertices_.id(), 0, vertices_.size()}; }
    BufferRange status() const { return {status_.id(), 0, status_.size()}; }
    /// The constants block lookups need (level 0 of the last build: size.x = R, size.w = levels).
    const DsmParams& params() const { return staging_[0]; }

    /// Builds the map. Per-frame contract: no allocation, no query, no read-back, no throw; a caster
    /// range that is too small is the integrator's error (PENUMBRA_ASSERT).
    /// `medium`: an optional participating medium (checkDsmMedium() it at load time).
    void build(const DsmLight& light, const DsmOpacity& opacity, const DsmCasterBuffers& casters, const DsmMedium& medium = {}) {
        PENUMBRA_ASSERT(casters.index_count % 3 == 0 && casters.indices.holds(4ull * casters.index_count));
        PENUMBRA_ASSERT(!casters.opacity_hook || !casters.hook_attribute.empty());
        const DsmSetup& s = setup_;
        DsmOpacity source;  // only the source kind and the mesh value matter here
        source.mesh = opacity.mesh;
        for (uint32_t level = 0; level < s.levels; ++level) {
            DsmParams p = deepShadowMapParams(s, light, source, level, medium);
            p.flags.x = casters.opacity_hook                ? PENUMBRA_DSM_OPACITY_HOOK
                        : !casters.vertex_opacity.empty()   ? PENUMBRA_DSM_OPACITY_VERTEX
                        : !casters.triangle_opacity.empty() ? PENUMBRA_DSM_OPACITY_TRIANGLE
                                                            : PENUMBRA_DSM_OPACITY_MESH;
            p.capacity.x = static_cast<uint32_t>(capacity_.fragments);
            p.capacity.y = static_cast<uint32_t>(capacity_.vertices);
            staging_[level] = p;
            glNamedBufferSubData(params_.id(), level * ubo_stride_, sizeof(DsmParams), &p);
        }
        const uint32_t zero = 0;
        // The last build's shaders wrote these buffers: a clear is ordered after those writes only
        // by this bit (GL 4.5 §7.13.2); llvmpipe is coherent anyway, real GPUs need not be.
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        glClearNamedBufferData(counts_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
        glClearNamedBufferData(cursor_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
        glClearNamedBufferData(status_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);

        bindAll(casters, 0);

        // 1-3: count, scan, scatter.
        glVertexArrayVertexBuffer(vao_, 0, casters.positions.buffer, static_cast<GLintptr>(casters.positions.offset), 12);
        const BufferRange& attribute = casters.opacity_hook ? casters.hook_attribute : casters.vertex_opacity;
        if (!attribute.empty()) {
            glEnableVertexArrayAttrib(vao_, 1);
            glVertexArrayVertexBuffer(vao_, 1, attribute.buffer, static_cast<GLintptr>(attribute.offset), 12);
            if (casters.opacity_hook && casters.opacity_texture != 0)
                glBindTextureUnit(PENUMBRA_DSM_OPACITY_TEXTURE_UNIT, casters.opacity_texture);
        } else {
            glDisableVertexArrayAttrib(vao_, 1);
        }
        glVertexArrayElementBuffer(vao_, casters.indices.buffer);
        glBindVertexArray(vao_);
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, fbo_);
        glViewport(0, 0, static_cast<GLsizei>(s.resolution), static_cast<GLsizei>(s.resolution));
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        glDisable(GL_RASTERIZER_DISCARD);
        gl::setPassRasterState();
        const void* first_index = reinterpret_cast<const void*>(static_cast<uintptr_t>(casters.indices.offset));
        timers_.begin(0);
        glUseProgram(raster_count_.id());
        glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(casters.index_count), GL_UNSIGNED_INT, first_index);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        scanner_.scan(ScanKind::Exclusive, {counts_.id(), 0, counts_.size()}, {counts_.id(), 0, counts_.size()}, lists_ + 1ull);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_UNIFORM_BARRIER_BIT);
        bindAll(casters, 0);  // the scan used bindings of its own
        glUseProgram(raster_scatter_.id());
        glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(casters.index_count), GL_UNSIGNED_INT, first_index);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        timers_.end();

        // 4: sort.
        timers_.begin(1);
        dispatch(sort_, lists_);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        timers_.end();

        // 5-6: merge + compress (level 0), then every mip level.
        for (uint32_t level = 0; level < s.levels; ++level) {
            const uint32_t r = s.level_resolution[level];
            const uint64_t word = s.level_texel_offset[level] + level;
            if (level <= 1) timers_.begin(level == 0 ? 2 : 3);
            bindLevel(level);
            const Program* programs = level == 0 ? merge_ : mip_;
            dispatch(programs[0], uint64_t(r) * r);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            const BufferRange range{offsets_.id(), 4 * word, 4 * (uint64_t(r) * r + 1)};
            scanner_.scan(ScanKind::Exclusive, range, range, uint64_t(r) * r + 1);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_UNIFORM_BARRIER_BIT);
            bindAll(casters, level);
            dispatch(programs[1], uint64_t(r) * r);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            if (level == 0 || level + 1 == s.levels) timers_.end();
        }
        if (s.levels == 1 && timers_.enabled()) {  // an empty mips stage
            timers_.begin(3);
            timers_.end();
        }
    }

    /// Batch lookups on the GPU (tests, tools): queries vec4 (u, v, depth, lod), results vec4.
    void lookup(const BufferRange& queries, const BufferRange& results, uint32_t count) {
        DsmParams p = staging_[0];
        p.capacity.x = count;
        glNamedBufferSubData(params_.id(), setup_.levels * ubo_stride_, sizeof(DsmParams), &p);
        gl::bindRange(GL_UNIFORM_BUFFER, PENUMBRA_DSM_BINDING_PARAMS, params_.id(),
                      static_cast<GLintptr>(setup_.levels * ubo_stride_), sizeof(DsmParams));
        gl::bindRange(GL_SHADER_STORAGE_BUFFER, 0, queries.buffer, static_cast<GLintptr>(queries.offset),
                      static_cast<GLsizeiptr>(queries.size));
        gl::bindRange(GL_SHADER_STORAGE_BUFFER, 2, results.buffer, static_cast<GLintptr>(results.offset),
                      static_cast<GLsizeiptr>(results.size));
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_DSM_BINDING_MAP_OFFSETS, offsets_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_DSM_BINDING_MAP_VERTICES, vertices_.id());
        dispatch(lookup_, count);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    }

    /// Read-backs (tests and tools only).
    DsmStatus readStatus() const {
        uint32_t w[PENUMBRA_DSM_STATUS_WORDS];
        glGetNamedBufferSubData(status_.id(), 0, sizeof(w), w);
        DsmStatus st;
        st.fragment_overflow = w[PENUMBRA_DSM_STATUS_FRAGMENT_OVERFLOW];
        st.vertex_overflow = w[PENUMBRA_DSM_STATUS_VERTEX_OVERFLOW];
        uint32_t total = 0;
        glGetNamedBufferSubData(counts_.id(), 4ull * lists_, 4, &total);
        st.fragments = total;
        return st;
    }

    /// The whole map as DsmMapCpu (same layout as buildDsmMapCpu's output).
    DsmMapCpu readMap() const {
        const DsmSetup& s = setup_;
        DsmMapCpu map;
        map.resolution = s.resolution;
        map.channels = s.channels;
        map.levels = s.levels;
        map.resolution_of = s.level_resolution;
        std::vector<uint32_t> words(offset_words_);
        glGetNamedBufferSubData(offsets_.id(), 0, static_cast<GLsizeiptr>(4 * offset_words_), words.data());
        const uint64_t cap = capacity_.vertices, C = s.channels;
        std::vector<uint32_t> vw(static_cast<size_t>(cap + (cap * C + 1) / 2));
        glGetNamedBufferSubData(vertices_.id(), 0, static_cast<GLsizeiptr>(4 * vw.size()), vw.data());
        map.packed = true;
        uint64_t base = 0, word = 0;
        const uint32_t F = s.vertexFloats();
        for (uint32_t l = 0; l < s.levels; ++l) {
            const uint32_t r = s.level_resolution[l];
            map.offsets.emplace_back(words.begin() + static_cast<ptrdiff_t>(word),
                                     words.begin() + static_cast<ptrdiff_t>(word + uint64_t(r) * r + 1));
            const uint64_t n = map.offsets.back().back();
            map.vertices.emplace_back(static_cast<size_t>(n * F), 0.0f);
            std::vector<float>& out = map.vertices.back();
            for (uint64_t i = 0; i < n && base + i < cap; ++i) {
                const uint64_t vertex = base + i;
                out[F * i] = ::penumbra::detail::floatFromBits(vw[vertex]);
                for (uint64_t c = 0; c < C; ++c) {
                    const uint64_t h = vertex * C + c;
                    const uint32_t w = vw[cap + h / 2];
                    out[F * i + 1 + c] = dsmDecode((h & 1) ? (w >> 16) : (w & 0xFFFFu));
                }
            }
            base += n;
            word += uint64_t(r) * r + 1;
        }
        return map;
    }

    /// The fragment lists after the sort (tests: the twin of buildDsmFragmentsCpu).
    DsmFragmentsCpu readFragments() const {
        DsmFragmentsCpu f;
        f.offsets.resize(lists_ + 1ull);
        glGetNamedBufferSubData(counts_.id(), 0, static_cast<GLsizeiptr>(4 * (lists_ + 1ull)), f.offsets.data());
        const uint64_t n = std::min<uint64_t>(f.offsets.back(), capacity_.fragments);
        const uint32_t words = setup_.channels == 3 ? 8 : 4;
        std::vector<uint32_t> raw(static_cast<size_t>(n * words));
        if (n) glGetNamedBufferSubData(records_.id(), 0, static_cast<GLsizeiptr>(4 * raw.size()), raw.data());
        f.fragments.resize(static_cast<size_t>(n));
        for (uint64_t i = 0; i < n; ++i) {
            const uint32_t* r = raw.data() + i * words;
            DsmFragment& d = f.fragments[i];
            d.z = ::penumbra::detail::floatFromBits(r[0]);
            d.triangle = r[1];
            d.alpha = glm::vec3(::penumbra::detail::floatFromBits(r[2]), words == 8 ? ::penumbra::detail::floatFromBits(r[3]) : d.alpha.y,
                                words == 8 ? ::penumbra::detail::floatFromBits(r[4]) : d.alpha.z);
            if (words == 4) d.alpha = glm::vec3(::penumbra::detail::floatFromBits(r[2]), 0.0f, 0.0f);
        }
        return f;
    }

private:
    void bindLevel(uint32_t level) {
        gl::bindRange(GL_UNIFORM_BUFFER, PENUMBRA_DSM_BINDING_PARAMS, params_.id(), static_cast<GLintptr>(level * ubo_stride_),
                      sizeof(DsmParams));
    }
    void bindAll(const DsmCasterBuffers& casters, uint32_t level) {
        bindLevel(level);
        gl::bindBase(GL_UNIFORM_BUFFER, PENUMBRA_CONSERVATIVE_PARAMS_BINDING, conservative_ubo_.id());
        if (!casters.triangle_opacity.empty()) {
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, PENUMBRA_DSM_BINDING_TRIANGLE_OPACITY, casters.triangle_opacity.buffer,
                          static_cast<GLintptr>(casters.triangle_opacity.offset),
                          static_cast<GLsizeiptr>(casters.triangle_opacity.size));
        } else {
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_DSM_BINDING_TRIANGLE_OPACITY, dummy_.id());
        }
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_DSM_BINDING_PATTERNS, patterns_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_DSM_BINDING_COUNTS, counts_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_DSM_BINDING_CURSOR, cursor_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_DSM_BINDING_RECORDS, records_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_DSM_BINDING_STATUS, status_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_DSM_BINDING_MAP_OFFSETS, offsets_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_DSM_BINDING_MAP_VERTICES, vertices_.id());
    }
    void dispatch(const Program& program, uint64_t invocations) {
        if (invocations == 0) return;
        const auto grid = ::penumbra::detail::foldDispatch(::penumbra::detail::divUp(invocations, PENUMBRA_DSM_GROUP_SIZE));
        glUseProgram(program.id());
        glDispatchCompute(grid.x, grid.y, 1);
    }

    DsmSetup setup_;
    DsmCapacity capacity_;
    ConservativeRasterSetup conservative_;
    Scanner scanner_;
    uint32_t lists_ = 0;
    uint64_t offset_words_ = 0;
    uint32_t ubo_stride_ = 256;
    Buffer patterns_, counts_, cursor_, records_, status_, offsets_, vertices_, dummy_, params_, conservative_ubo_;
    std::vector<DsmParams> staging_;
    Program raster_count_, raster_scatter_, sort_, merge_[2], mip_[2], lookup_;
    GLuint vao_ = 0, fbo_ = 0;
    StageTimers<4> timers_;
};

}  // namespace penumbra::gl

#endif
