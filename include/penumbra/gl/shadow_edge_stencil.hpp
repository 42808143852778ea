// penumbra — eye-view anti-aliasing of irregular hard shadows (galoppo2010) on the GPU: the provable
// shadow-edge stencil, the extended sample buffer and the resolve. The rules, the pure setup and the
// CPU twins are penumbra/shadow_edge_stencil.hpp; this header runs them.
//
// Integration summary
//   needs:    GL 4.5 with fp64 in shaders and geometry shaders; PENUMBRA_GL_HEADER; a scan block
//             (the stencil owns one Scanner); the engine's per-pixel view samples (vec4 world
//             positions, w == 0: none) and face normals (vec4) as buffer ranges, P = W_view x
//             H_view each; casters as a vec3 float vertex range + uint32 index range (GL_TRIANGLES).
//   produces: subSamples() (vec4 [P * N]: pixel i's sub-sample k at i N + k), stencil() (uint [P]:
//             PENUMBRA_AA_FLAG | PENUMBRA_AA_SHADOWED | PENUMBRA_AA_LIT), then on request the hard
//             pipeline's input (writeSampleBuffer: positions + normals [sampleCount(mode, budget)],
//             the layout of aaSampleBuffer: edge mode packs the flagged pixels' sub-samples, ranked
//             by a scan, up to a budget of pixels; with the provable stencil the pixels it did not
//             flag are no samples, AaUnflagged::Proven) and per-pixel visibility from the hard
//             pipeline's states and, for those pixels, the stencil's verdict (resolve).
//   per frame: run() — (1) sub-samples + facing, (2) footprint boxes and counts per light texel,
//             (3) exclusive scan, (4) scatter, (5) the footprint light pass: every caster drawn with
//             the conservative emitter into an attachment-less grid; each fragment classifies its
//             texel's footprints against the triangle (sphere test, exact test where undecided),
//             (6) final bits. Then writeSampleBuffer (edge: flags, scan, pack), the engine's
//             AliasFreeHardShadows on its sampleCount() samples, resolve() with their states.
//             Nothing is read back, queried, allocated or thrown per frame: misuse returns a Status.
//   equals:   the CPU twin (aaFootprintsCpu, provableEdgeStencilCpu with the same options; casters
//             not culled) bit for bit where fp64 + - * / sqrt are correctly rounded (llvmpipe) and
//             no list entry overflowed (readStatus()[PENUMBRA_AA_STATUS_LIST_OVERFLOW] == 0; an
//             overflowing pixel is flagged: safe, merely multi-sampled).
//   state:    run() binds its programs, vertex array, framebuffer, viewport (grid size), uniform
//             bindings 0-1 and storage bindings 0-7 and what the scanner binds; disables depth test,
//             culling and rasterizer discard; sets gl::setPassRasterState's rasterizer state
//             (scissor off, polygon fill, clip distances off, clip control lower-left / -1..1, no
//             primitive restart, ...); restores none of them. Ends with
//             GL_SHADER_STORAGE_BARRIER_BIT.
#ifndef PENUMBRA_GL_SHADOW_EDGE_STENCIL_HPP
#define PENUMBRA_GL_SHADOW_EDGE_STENCIL_HPP

#include "penumbra/buffer_range.hpp"
#include "penumbra/conservative_raster.hpp"
#include "penumbra/detail/dispatch.hpp"
#include "penumbra/gl/gl.hpp"
#include "penumbra/gl/objects.hpp"
#include "penumbra/gl/scan.hpp"
#include "penumbra/gl/shader.hpp"
#include "penumbra/gl/validate.hpp"
#include "penumbra/shadow_edge_stencil.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

namespace penumbra::gl {

/// The casters of one run (every triangle casts: no class culling).
struct AaCasterBuffers {
    BufferRange positions;  ///< vec3 float position per vertex, `stride` bytes apart
    BufferRange indices;    ///< uint32, 3 per triangle
    uint32_t index_count = 0;
    uint32_t stride = 12;   ///< bytes from one vertex's position to the next (interleaved attributes)
};

/// Which stencil run() computes: the provable one (default) or galoppo2010's Chebyshev stencil
/// over a conservative moment map (a probability: it can miss edges; its moments equal
/// conservativeMomentMapCpu's and its flags chebyshevEdgeStencilCpu's).
enum class AaStencilKind { Provable, Chebyshev };

class ShadowEdgeStencil {
public:
    /// options: the hard pipeline's options (grid_width x grid_height = the binning grid, the
    /// coplanar epsilon, directional_reach); pattern: rotated grid, N in [1, 64]; list_capacity:
    /// footprint-texel entries the lists hold (over it: pixels flagged, counted in the status).
    /// Throws penumbra::Error for bad sizes or options (setup time).
    ShadowEdgeStencil(uint32_t view_width, uint32_t view_height, const AliasFreeHardOptions& options,
                      const AaPatternOptions& pattern = {}, const ProvableStencilOptions& stencil_options = {},
                      uint32_t list_capacity = 1u << 22, const ShaderLibrary& library = ShaderLibrary::embedded(),
                      AaStencilKind kind = AaStencilKind::Provable, const ChebyshevStencilOptions& chebyshev = {})
        : width_(view_width), height_(view_height), options_(options), pattern_(pattern), stencil_options_(stencil_options),
          capacity_(list_capacity), kind_(kind), chebyshev_(chebyshev), scanner_(ScanOptions{}, library) {
        checkAaPatternOptions(pattern);
        PENUMBRA_CHECK(pattern.pattern == AaPattern::RotatedGrid,
                       "ShadowEdgeStencil: the GPU stencil runs the rotated-grid pattern only (jittered: the CPU path)");
        PENUMBRA_CHECK(view_width > 0 && view_height > 0 && uint64_t(view_width) * view_height * (1 + pattern.samples) < (1ull << 31),
                       "ShadowEdgeStencil: view ", view_width, "x", view_height, " with ", pattern.samples,
                       " sub-samples is empty or past 2^31 samples");
        PENUMBRA_CHECK(options.precision == AfhPrecision::Exact && options.sample_offset == 0.0f && !options.back_faces_only &&
                           !options.light_facing_only,
                       "ShadowEdgeStencil: needs the exact hard pipeline without caster culling");
        validateAliasFreeHardOptions(options, glm::vec4(0, 0, 0, 1));
        PENUMBRA_CHECK(list_capacity >= 1, "ShadowEdgeStencil: list capacity must be >= 1");
        pixels_ = view_width * view_height;
        const uint64_t texels = uint64_t(options.grid_width) * options.grid_height;
        ConservativeRasterOptions cr;
        cr.viewport_width = static_cast<int>(options.grid_width);
        cr.viewport_height = static_cast<int>(options.grid_height);
        cr.variant = ConservativeVariant::Exact;
        cr.near_plane = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);  // w >= min_w only, as the hard pipeline's light pass
        conservative_ = conservativeRasterSetup(cr);

        sub_samples_ = Buffer(16ull * pixels_ * pattern.samples);
        stencil_ = Buffer(4ull * pixels_);
        footprints_ = Buffer(sizeof(AaFootprintRecord) * pixels_);
        counts_ = Buffer(4 * (texels + 1));
        cursor_ = Buffer(4 * texels);
        list_ = Buffer(4ull * list_capacity);
        status_ = Buffer(4 * PENUMBRA_AA_STATUS_WORDS);
        params_ = Buffer(sizeof(AaParams), nullptr, GL_DYNAMIC_STORAGE_BIT);
        conservative_ubo_ = Buffer(sizeof(ConservativeRasterParams), &conservative_.params, GL_DYNAMIC_STORAGE_BIT);
        ranks_ = Buffer(4ull * (pixels_ + 1));
        const uint32_t zero = 0;
        glClearNamedBufferData(ranks_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
        scanner_.reserve(std::max<uint64_t>(texels, pixels_) + 1);

        footprints_program_ = buildComputeProgram("penumbra/shadow_edge_stencil/footprints.comp.glsl", {}, library);
        setup_program_[0] = buildComputeProgram("penumbra/shadow_edge_stencil/setup.comp.glsl", {{"PENUMBRA_AA_PASS", "0"}}, library);
        setup_program_[1] = buildComputeProgram("penumbra/shadow_edge_stencil/setup.comp.glsl", {{"PENUMBRA_AA_PASS", "1"}}, library);
        classify_program_ = buildProgram({"penumbra/shadow_edge_stencil/classify.vert.glsl",
                                          "penumbra/shadow_edge_stencil/classify.geom.glsl",
                                          "penumbra/shadow_edge_stencil/classify.frag.glsl"},
                                         conservative_.defines, library);
        finish_program_ = buildComputeProgram("penumbra/shadow_edge_stencil/finish.comp.glsl", {}, library);
        buffer_program_ = buildComputeProgram("penumbra/shadow_edge_stencil/sample_buffer.comp.glsl", {}, library);
        ranks_program_ = buildComputeProgram("penumbra/shadow_edge_stencil/ranks.comp.glsl", {}, library);
        resolve_program_ = buildComputeProgram("penumbra/shadow_edge_stencil/resolve.comp.glsl", {}, library);
        if (kind == AaStencilKind::Chebyshev) {
            PENUMBRA_CHECK(chebyshev.threshold > 0.0f && chebyshev.threshold < 1.0f && chebyshev.bias_scale >= 0.0f &&
                               chebyshev.min_variance > 0.0f,
                           "ShadowEdgeStencil: Chebyshev threshold ", chebyshev.threshold, " must be in (0, 1), bias_scale ",
                           chebyshev.bias_scale, " >= 0, min_variance ", chebyshev.min_variance, " > 0");
            levels_ = aaMomentLevels(options.grid_width, options.grid_height);
            uint64_t level_texels = 0;
            for (uint32_t l = 0; l < levels_; ++l)
                level_texels += uint64_t(std::max(1u, options.grid_width >> l)) * std::max(1u, options.grid_height >> l);
            min_depth_ = Buffer(4 * texels);
            min_cover_ = Buffer(4 * texels);
            moments_ = Buffer(8 * level_texels);
            covers_ = Buffer(4 * level_texels);
            moments_raster_ = buildProgram({"penumbra/shadow_edge_stencil/moments.vert.glsl",
                                            "penumbra/shadow_edge_stencil/moments.geom.glsl",
                                            "penumbra/shadow_edge_stencil/moments.frag.glsl"},
                                           conservative_.defines, library);
            moments_level_[0] = buildComputeProgram("penumbra/shadow_edge_stencil/moments_level.comp.glsl", {{"PENUMBRA_AA_PASS", "0"}}, library);
            moments_level_[1] = buildComputeProgram("penumbra/shadow_edge_stencil/moments_level.comp.glsl", {{"PENUMBRA_AA_PASS", "1"}}, library);
            chebyshev_program_ = buildComputeProgram("penumbra/shadow_edge_stencil/chebyshev.comp.glsl", {}, library);
        }

        glCreateVertexArrays(1, &vao_);
        glEnableVertexArrayAttrib(vao_, 0);
        glVertexArrayAttribFormat(vao_, 0, 3, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(vao_, 0, 0);
        glCreateFramebuffers(1, &fbo_);
        glNamedFramebufferParameteri(fbo_, GL_FRAMEBUFFER_DEFAULT_WIDTH, static_cast<GLint>(options.grid_width));
        glNamedFramebufferParameteri(fbo_, GL_FRAMEBUFFER_DEFAULT_HEIGHT, static_cast<GLint>(options.grid_height));
    }
    ShadowEdgeStencil(const ShadowEdgeStencil&) = delete;
    ShadowEdgeStencil& operator=(const ShadowEdgeStencil&) = delete;
    ~ShadowEdgeStencil() {
        if (vao_) glDeleteVertexArrays(1, &vao_);
        if (fbo_) glDeleteFramebuffers(1, &fbo_);
    }

    uint32_t pixels() const { return pixels_; }
    uint32_t samples() const { return pattern_.samples; }
    /// Bytes of each of writeSampleBuffer's ranges: P (1 + N) vec4 (every mode and budget fits).
    uint64_t sampleBufferBytes() const { return 16ull * pixels_ * (1 + pattern_.samples); }
    /// Samples of writeSampleBuffer's layout (the hard pipeline's sample count and the states
    /// resolve() reads): P (Off), P (1 + N) (Full), P + min(budget, P) N (Edge).
    uint32_t sampleCount(AaMode mode, uint32_t budget = kAaAllPixels) const {
        return static_cast<uint32_t>(aaSampleCount(mode, pixels_, pattern_.samples, budget));
    }

    /// The stencil of one frame (see the header comment). centres/normals: P vec4 each; `view` the
    /// engine's camera (its size must be the constructor's); `light.view_projection` must see every
    /// centre and sub-sample (pixels with a point outside are flagged).
    Status run(const BufferRange& centres, const BufferRange& normals, const SampleListsView& view,
               const SampleListsLight& light, const AaCasterBuffers& casters) {
        if (view.width != width_ || view.height != height_) return Status::InvalidArgument;
        if (centres.size < 16ull * pixels_ || normals.size < 16ull * pixels_ || !centres.buffer || !normals.buffer)
            return Status::RangeTooSmall;
        if (casters.index_count % 3 != 0 || casters.indices.size < 4ull * casters.index_count ||
            (casters.index_count > 0 && (!casters.positions.buffer || !casters.indices.buffer)))
            return Status::RangeTooSmall;
        if (centres.offset % 16 || normals.offset % 16 || casters.indices.offset % 4 || casters.stride < 12 || casters.stride % 4)
            return Status::Misaligned;
        if (!(light.light.w == 0.0f || light.light.w == 1.0f)) return Status::InvalidArgument;
        centres_ = centres;
        normals_ = normals;
        ranked_ = false;  // the edge layout's ranks follow this run's flags: writeSampleBuffer(Edge) again
        params_staging_ = aaParams(view, light, options_, pattern_, stencil_options_, capacity_, PENUMBRA_AA_MODE_EDGE, chebyshev_);
        glNamedBufferSubData(params_.id(), 0, sizeof(AaParams), &params_staging_);
        const uint32_t zero = 0;
        // The last run's shaders wrote these buffers (and the Chebyshev maps cleared below): a
        // clear is ordered after those writes only by this bit (GL 4.5 §7.13.2).
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        glClearNamedBufferData(counts_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
        glClearNamedBufferData(cursor_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
        glClearNamedBufferData(status_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);

        // (1) sub-samples and facing.
        bindCommon();
        bindRange(PENUMBRA_AA_BINDING_NORMALS, normals_);
        dispatch(footprints_program_, pixels_);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        if (kind_ == AaStencilKind::Chebyshev) {
            runChebyshev(casters);
            ran_ = true;
            return Status::Ok;
        }
        // (2) boxes and counts, (3) scan, (4) scatter.
        bindStencilPass();
        dispatch(setup_program_[0], pixels_);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        const uint64_t texels = uint64_t(options_.grid_width) * options_.grid_height;
        scanner_.scan(ScanKind::Exclusive, {counts_.id(), 0, counts_.size()}, {counts_.id(), 0, counts_.size()}, texels + 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_UNIFORM_BARRIER_BIT);
        bindStencilPass();  // the scan used bindings of its own
        dispatch(setup_program_[1], pixels_);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        // (5) the footprint light pass.
        drawCasters(classify_program_, casters);
        // (6) final bits.
        dispatch(finish_program_, pixels_);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        ran_ = true;
        return Status::Ok;
    }

    /// The hard pipeline's input for `mode` from the last run: positions and normals,
    /// 16 sampleCount(mode, budget) bytes each, 16-byte aligned (aaSampleBuffer's layout). Full:
    /// every pixel's sub-samples. Edge: the flagged pixels' packed in pixel order (ranked by a
    /// scan), the first `budget` of them, whose centre slots get w == 0 (the resolve reads their
    /// sub-samples only, so the lists skip the centres); with the provable stencil (the default
    /// kind) so do the unflagged pixels' (their states are the stencil's proven verdicts,
    /// AaUnflagged::Proven): the hard pipeline tests the flagged pixels' sub-samples alone. The
    /// Chebyshev kind keeps them (its claims are not proofs). The engine runs the hard pipeline on
    /// sampleCount(Edge, budget) samples, so a budget near the flagged count (e.g. the last
    /// frame's plus a margin) skips the empty slots. Flagged pixels past it stay single-sampled
    /// (resolve() counts them: readStatus()[PENUMBRA_AA_STATUS_BUDGET_OVERFLOW]); the default
    /// holds every pixel.
    Status writeSampleBuffer(AaMode mode, const BufferRange& positions, const BufferRange& normals,
                             uint32_t budget = kAaAllPixels) {
        if (!ran_) return Status::NotReserved;
        if (mode == AaMode::Off) return Status::InvalidArgument;
        const uint64_t bytes = 16ull * sampleCount(mode, budget);
        if (positions.size < bytes || normals.size < bytes || !positions.buffer || !normals.buffer) return Status::RangeTooSmall;
        if (positions.offset % 16 || normals.offset % 16) return Status::Misaligned;
        setMode(mode, budget);
        if (mode == AaMode::Edge) {
            rankFlaggedPixels();
            ranked_ = true;
        }
        bindCommon();
        bindRange(PENUMBRA_AA_BINDING_NORMALS, normals_);
        bindRange(PENUMBRA_AA_BINDING_OUT_POSITIONS, positions);
        bindRange(PENUMBRA_AA_BINDING_OUT_NORMALS, normals);
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_RANKS, ranks_.id());
        dispatch(buffer_program_, pixels_);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        return Status::Ok;
    }

    /// Per-pixel visibility (float [P]) from the hard pipeline's states, sampleCount(mode, budget)
    /// of them in writeSampleBuffer's layout (Off: the P centres'); Edge takes the budget (and the
    /// ranks) of the last writeSampleBuffer(Edge) since run() (NotReserved without one); with the
    /// provable stencil, an unflagged pixel's value is its verdict (1 where PENUMBRA_AA_LIT, else 0).
    Status resolve(AaMode mode, const BufferRange& states, const BufferRange& visible, uint32_t budget = kAaAllPixels) {
        if (mode != AaMode::Off && !ran_) return Status::NotReserved;
        if (mode == AaMode::Edge && !ranked_) return Status::NotReserved;
        const uint64_t need = 4ull * sampleCount(mode, budget);
        if (states.size < need || visible.size < 4ull * pixels_ || !states.buffer || !visible.buffer) return Status::RangeTooSmall;
        if (states.offset % 4 || visible.offset % 4) return Status::Misaligned;
        if (!ran_) {  // Off before any run: the parameter block still needs the sizes
            params_staging_.view = glm::uvec4(width_, height_, pattern_.samples, 1u);
            glNamedBufferSubData(params_.id(), 0, sizeof(AaParams), &params_staging_);
        }
        setMode(mode, budget);
        bindCommon();
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_STATUS, status_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_RANKS, ranks_.id());
        bindRange(PENUMBRA_AA_BINDING_STATES, states);
        bindRange(PENUMBRA_AA_BINDING_VISIBLE, visible);
        dispatch(resolve_program_, pixels_);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        return Status::Ok;
    }

    const Buffer& subSamples() const { return sub_samples_; }
    const Buffer& stencil() const { return stencil_; }
    /// Read-backs (they wait for the GPU): for tests and tools, not for the frame.
    std::vector<uint32_t> readStencil() const { return stencil_.download<uint32_t>(); }
    std::vector<glm::vec4> readSubSamples() const { return sub_samples_.download<glm::vec4>(); }
    /// The Chebyshev kind's moment map, every level one after another (E(x), E(x^2)) and the
    /// inner-coverage values (the layout of MomentMapCpu::levels / cover, concatenated).
    std::vector<glm::vec2> readMoments() const { return moments_.download<glm::vec2>(); }
    std::vector<float> readCovers() const { return covers_.download<float>(); }
    std::array<uint32_t, PENUMBRA_AA_STATUS_WORDS> readStatus() const {
        const std::vector<uint32_t> s = status_.download<uint32_t>();
        std::array<uint32_t, PENUMBRA_AA_STATUS_WORDS> out{};
        for (size_t i = 0; i < out.size(); ++i) out[i] = s[i];
        return out;
    }

private:
    void drawCasters(const Program& program, const AaCasterBuffers& casters) {
        if (casters.index_count == 0) return;
        gl::bindBase(GL_UNIFORM_BUFFER, PENUMBRA_CONSERVATIVE_PARAMS_BINDING, conservative_ubo_.id());
        glVertexArrayVertexBuffer(vao_, 0, casters.positions.buffer, static_cast<GLintptr>(casters.positions.offset),
                                  static_cast<GLsizei>(casters.stride));
        glVertexArrayElementBuffer(vao_, casters.indices.buffer);
        glBindVertexArray(vao_);
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, fbo_);
        glViewport(0, 0, static_cast<GLsizei>(options_.grid_width), static_cast<GLsizei>(options_.grid_height));
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        glDisable(GL_RASTERIZER_DISCARD);
        gl::setPassRasterState();
        glUseProgram(program.id());
        glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(casters.index_count), GL_UNSIGNED_INT,
                       reinterpret_cast<const void*>(static_cast<uintptr_t>(casters.indices.offset)));
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }
    // galoppo2010 steps 1-3: the conservative moment map (raster with atomicMin, level 0, mips),
    // then the Chebyshev test per pixel.
    void runChebyshev(const AaCasterBuffers& casters) {
        // Empty texels: d_far (0 for a perspective light's -1/w, 2 beyond z_ndc); no cover (+inf).
        const uint32_t empty_depth = params_staging_.moments.z ? 0x80000000u : 0xC0000000u, no_cover = 0xFF800000u;
        glClearNamedBufferData(min_depth_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &empty_depth);
        glClearNamedBufferData(min_cover_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &no_cover);
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_MIN_DEPTH, min_depth_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_MIN_COVER, min_cover_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_MOMENTS, moments_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_COVERS, covers_.id());
        drawCasters(moments_raster_, casters);
        dispatch(moments_level_[0], uint64_t(options_.grid_width) * options_.grid_height);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        for (uint32_t l = 1; l < levels_; ++l) {
            params_staging_.moments.w = l;
            glNamedBufferSubData(params_.id(), offsetof(AaParams, moments), sizeof(glm::uvec4), &params_staging_.moments);
            dispatch(moments_level_[1], uint64_t(std::max(1u, options_.grid_width >> l)) * std::max(1u, options_.grid_height >> l));
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        }
        dispatch(chebyshev_program_, pixels_);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }
    void setMode(AaMode mode, uint32_t budget) {
        // Edge with the provable stencil: unflagged pixels are decided by its word (no sample).
        const uint32_t edge = kind_ == AaStencilKind::Provable ? PENUMBRA_AA_MODE_EDGE_PROVEN : PENUMBRA_AA_MODE_EDGE;
        params_staging_.grid.w = mode == AaMode::Off ? PENUMBRA_AA_MODE_OFF : mode == AaMode::Edge ? edge : PENUMBRA_AA_MODE_FULL;
        params_staging_.limits.z = std::min(budget, pixels_);
        glNamedBufferSubData(params_.id(), offsetof(AaParams, grid), sizeof(glm::uvec4), &params_staging_.grid);
        glNamedBufferSubData(params_.id(), offsetof(AaParams, limits), sizeof(glm::uvec4), &params_staging_.limits);
    }
    // The edge layout's ranks: 1 per flagged pixel (and 0 at entry P), exclusive-scanned in place.
    void rankFlaggedPixels() {
        bindCommon();
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_RANKS, ranks_.id());
        dispatch(ranks_program_, uint64_t(pixels_) + 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        scanner_.scan(ScanKind::Exclusive, {ranks_.id(), 0, ranks_.size()}, {ranks_.id(), 0, ranks_.size()}, uint64_t(pixels_) + 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_UNIFORM_BARRIER_BIT);
    }
    static void bindRange(GLuint binding, const BufferRange& r) {
        gl::bindRange(GL_SHADER_STORAGE_BUFFER, binding, r.buffer, static_cast<GLintptr>(r.offset), static_cast<GLsizeiptr>(r.size));
    }
    void bindCommon() {
        gl::bindBase(GL_UNIFORM_BUFFER, PENUMBRA_AA_BINDING_PARAMS, params_.id());
        if (centres_.buffer) bindRange(PENUMBRA_AA_BINDING_CENTRES, centres_);
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_SUB_SAMPLES, sub_samples_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_STENCIL, stencil_.id());
    }
    void bindStencilPass() {
        bindCommon();
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_STATUS, status_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_FOOTPRINTS, footprints_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_COUNTS, counts_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_CURSOR, cursor_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AA_BINDING_LIST, list_.id());
    }
    void dispatch(const Program& program, uint64_t invocations) {
        if (invocations == 0) return;
        const auto grid = ::penumbra::detail::foldDispatch(::penumbra::detail::divUp(invocations, PENUMBRA_AA_GROUP_SIZE));
        glUseProgram(program.id());
        glDispatchCompute(grid.x, grid.y, 1);
    }

    uint32_t width_ = 0, height_ = 0, pixels_ = 0;
    AliasFreeHardOptions options_;
    AaPatternOptions pattern_;
    ProvableStencilOptions stencil_options_;
    uint32_t capacity_ = 0;
    AaStencilKind kind_ = AaStencilKind::Provable;
    ChebyshevStencilOptions chebyshev_;
    uint32_t levels_ = 0;
    ConservativeRasterSetup conservative_;
    Scanner scanner_;
    AaParams params_staging_{};
    BufferRange centres_{}, normals_{};
    bool ran_ = false, ranked_ = false;
    Buffer sub_samples_, stencil_, footprints_, counts_, cursor_, list_, status_, params_, conservative_ubo_, ranks_;
    Buffer min_depth_, min_cover_, moments_, covers_;
    Program footprints_program_, setup_program_[2], classify_program_, finish_program_, buffer_program_, resolve_program_,
        ranks_program_;
    Program moments_raster_, moments_level_[2], chebyshev_program_;
    GLuint vao_ = 0, fbo_ = 0;
};

}  // namespace penumbra::gl

#endif
