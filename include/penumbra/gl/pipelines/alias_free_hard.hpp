// penumbra — alias-free hard shadows (sintorn2008 §3, Fig. 2–4) on the GPU: the executor of the
// first pipeline, composed only from the blocks' public APIs (penumbra/gl/sample_lists.hpp, the
// conservative emitter's GLSL). Options, pure setup and the CPU twin: penumbra/pipelines/
// alias_free_hard.hpp (no GL). Use it whole or copy it as a template.
//
// Integration summary
//   needs:    a GL 4.5 context with fp64 in shaders (exact mode, GPU fit) and, for the raster
//             light pass (the default), geometry shaders; PENUMBRA_GL_HEADER (gl/gl.hpp); shaders
//             penumbra/alias_free_hard/*.
//   compute:  options.light_pass = AfhLightPass::Compute: run() takes the casters as CasterBuffer
//             ranges (validateCasters() once at load time) instead of a DrawCasters callback; the
//             light pass is a setup dispatch per range piece, a scan and per list block one
//             indirect tiles dispatch per chunk of compute_triangles triangles (same states; no
//             draw, query, stencil or framebuffer; no geometry shader compiled). Its GL state:
//             the current program, the AfhBindings storage bindings counts .. args and header,
//             the uniform bindings params, frustum and 0 (conservative parameters), the
//             GL_DISPATCH_INDIRECT_BUFFER binding (the args), and what the scanner binds
//             (gl/scan.hpp), then the resolve's.
//   setup:    AliasFreeHardShadows(options, library, bindings) compiles everything; reserve(max
//             samples) allocates the lists, shadow bits, states and queries; validate(input, n)
//             checks the integrator's ranges/textures once (GL queries, throws).
//   input:    view samples as ranges of vec4 world positions (w == 0 = none) and vec4 normals
//             (SampleBufferInput), or the engine's depth buffer + normal texture + inverse
//             view-projection (SampleDepthInput: positions reconstructed on the GPU, the realistic
//             input); the light (SampleListsLight: point, light.w = 1, or directional, w = 0) with a
//             starting view-projection that sees every sample (lightViewProjectionForBounds); and
//             a callback that draws your casters of one class (closed or open) while the pipeline's
//             light-pass program is bound. Caster positions reach the vertex stage through the hook
//             penumbraAfhCasterPosition() (penumbra/alias_free_hard/caster_position.glsl, attribute 0
//             by default): replace that file in your ShaderLibrary for skinning, instancing or
//             packed positions. Everything in one frame — relative to a double origin far away.
//   produces: one uint state per view-sample id (PENUMBRA_AFH_LIT, _SHADOWED, _BACK_FACING,
//             _NO_SAMPLE, _UNTESTED; alias_free_hard_shared.h) in states() or your range, the
//             packed shadow bit per list slot, the lists themselves; on request (readFrame(), which
//             waits for the GPU) the fit, Fig. 9 statistics, passes, overflow and work counters.
//   per frame: run() — (1) §4.3 fit on the GPU into the frustum block, (2) lists (count, scan,
//             scatter) + statistics, (3) a predicate pass: one point per list block inside an
//             occlusion query, surviving when the longest list needs that block, (3b) with
//             skip_empty_texels (default) an occupancy pass per needed block: a full-screen
//             triangle increments a W x H GL_STENCIL_INDEX8 stencil where the texel's block b holds
//             samples, (4) light pass: for each block b < max_list_blocks, under
//             glBeginConditionalRender(query b), every caster drawn into a W x H framebuffer (no
//             colour attachment; the stencil, tested GL_LESS b with early fragment tests, culls the
//             fragments of texels with nothing in block b); the geometry stage culls
//             (closed casters with back_faces_only: only light-back-facing triangles, §3.3; with
//             light_facing_only: only those that do not face away from the light, exact) and
//             emits the triangle's conservative coverage; each fragment walks its texel's list
//             block and ORs the shadow bit of every sample the triangle blocks (4 planes), (5)
//             resolve. Nothing is read back, queried, allocated or thrown: misuse returns a Status.
//   Fixed-6 (default variant, fixed6_two_pass): step (4) is penumbra/conservative_raster's
//             two-pass plan, inside each block's conditional render: reset the spill header
//             (gl::beginConservativeSpill) and the spill-world counter, both caster classes through
//             the direct program (geometry stage max_vertices = 6, the seed's §3.2 figure), which
//             appends each triangle that needs clipping (it crosses the light's eye plane or the
//             guard band) with its world-space vertices to the spill buffers, then one
//             glDrawArraysIndirect of the spill program (max_vertices 13) whose command is the
//             spill header (gl::drawConservativeSpill: barrier, indirect draw, no attributes).
//             Same fragments, same states as the single pass. The spill buffers (112 bytes per
//             triangle, AliasFreeHardOptions::spill_capacity) are allocated at construction; an
//             overflow loses triangles (shadows may be missing) and is reported by readFrame()
//             (spill_overflow). Block 0's spill header is copied on the GPU into the work buffer.
//
// GL state: changes without restoring the current program, the draw framebuffer binding (the
// pipeline's own), the viewport, GL_DEPTH_TEST (off), GL_CULL_FACE (off), GL_RASTERIZER_DISCARD
// (off), GL_DEPTH_CLAMP (left on: casters before the near / beyond the far plane still cast),
// GL_STENCIL_TEST (off), the stencil function, operations and write mask (0 at the end) with
// skip_empty_texels, the
// rasterizer state of gl::setPassRasterState (scissor test off, polygon fill, clip distances
// off, clip control lower-left / -1..1, depth range [0, 1], no smoothing, offset or primitive
// restart, CCW, last provoking vertex: whatever the engine left there cannot clip or thin the
// predicate and light passes), the vertex-array binding (its own empty VAO during the predicate pass and the spill passes; then
// whatever your callback binds, or, two-pass, the empty VAO again), the uniform-buffer bindings of
// AfhBindings and 0 (conservative parameters), SSBO bindings of AfhBindings, the
// GL_DRAW_INDIRECT_BUFFER binding (two-pass: the spill buffer), and whatever the sample-list
// builder and scanner bind. Your caster callback must leave the light pass's SSBO bindings
// (counts, offsets, positions, shadow, work, spill, spill_world) alone. Ends with
// GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT.
#ifndef PENUMBRA_GL_PIPELINES_ALIAS_FREE_HARD_HPP
#define PENUMBRA_GL_PIPELINES_ALIAS_FREE_HARD_HPP

#include "penumbra/buffer_range.hpp"
#include "penumbra/gl/conservative_raster.hpp"
#include "penumbra/gl/objects.hpp"
#include "penumbra/gl/sample_lists.hpp"
#include "penumbra/gl/scan.hpp"
#include "penumbra/gl/shader.hpp"
#include "penumbra/gl/validate.hpp"
#include "penumbra/pipelines/alias_free_hard.hpp"

#include <cstddef>
#include <cstring>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace penumbra {

/// Binding points of the light pass and the resolve; value-initialised = alias_free_hard_shared.h.
struct AfhBindings {
    uint32_t params = PENUMBRA_AFH_PARAMS_BINDING;    ///< uniform block
    uint32_t frustum = PENUMBRA_AFH_FRUSTUM_BINDING;  ///< uniform block
    uint32_t counts = PENUMBRA_AFH_COUNTS_BINDING;    ///< SSBOs from here on
    uint32_t offsets = PENUMBRA_AFH_OFFSETS_BINDING;
    uint32_t positions = PENUMBRA_AFH_POSITIONS_BINDING;
    uint32_t shadow = PENUMBRA_AFH_SHADOW_BINDING;
    uint32_t work = PENUMBRA_AFH_WORK_BINDING;
    uint32_t header = PENUMBRA_AFH_HEADER_BINDING;
    uint32_t slots = PENUMBRA_AFH_SLOTS_BINDING;
    uint32_t texels = PENUMBRA_AFH_TEXELS_BINDING;
    uint32_t states = PENUMBRA_AFH_STATES_BINDING;
    uint32_t spill = PENUMBRA_AFH_SPILL_BINDING;              ///< Fixed-6 two-pass light pass only
    uint32_t spill_world = PENUMBRA_AFH_SPILL_WORLD_BINDING;  ///< Fixed-6 two-pass light pass only
    uint32_t caster_positions = PENUMBRA_AFH_CASTER_POSITIONS_BINDING;  ///< AfhLightPass::Compute: CasterBuffer::positions
    uint32_t caster_indices = PENUMBRA_AFH_CASTER_INDICES_BINDING;      ///< AfhLightPass::Compute: CasterBuffer::indices
    uint32_t triangles = PENUMBRA_AFH_TRIANGLES_BINDING;                ///< AfhLightPass::Compute: setup records
    uint32_t items = PENUMBRA_AFH_ITEMS_BINDING;                        ///< AfhLightPass::Compute: tiles per record, scanned
    uint32_t args = PENUMBRA_AFH_ARGS_BINDING;                          ///< AfhLightPass::Compute: the tiles pass's groups
    SampleListsBindings lists{};  ///< the sample-list builder's
};

/// The pipeline: owns its programs, the list/shadow/state buffers and its GL objects (RAII,
/// movable, not copyable).
class AliasFreeHardShadows {
public:
    using DrawCasters = std::function<void(CasterClass)>;

    explicit AliasFreeHardShadows(const AliasFreeHardOptions& options,
                                  const ShaderLibrary& library = ShaderLibrary::embedded(),
                                  const AfhBindings& bindings = {})
        : options_(options), bindings_(bindings), builder_(library, {}, bindings.lists) {
        validateAliasFreeHardOptions(options_, glm::vec4(0, 0, 0, 1));
        conservative_ = afhConservativeSetup(options_);
        ShaderDefines defines = conservative_.defines;
        defines.push_back({"PENUMBRA_AFH_EXACT", options_.precision == AfhPrecision::Exact ? "1" : "0"});
        // blocker_test.glsl: float filter with a proven bound in front of the double test (same bits).
        defines.push_back({"PENUMBRA_AFH_FILTERED", options_.fp64_only ? "0" : "1"});
        defines.push_back({"PENUMBRA_AFH_COUNT_WORK", options_.count_work ? "1" : "0"});
        defines.push_back({"PENUMBRA_AFH_SKIP_SHADOWED", options_.skip_shadowed ? "1" : "0"});
        const AfhBindings& b = bindings_;
        const std::pair<const char*, uint32_t> binding_defines[] = {
            {"PENUMBRA_AFH_PARAMS_BINDING", b.params}, {"PENUMBRA_AFH_FRUSTUM_BINDING", b.frustum},
            {"PENUMBRA_AFH_COUNTS_BINDING", b.counts}, {"PENUMBRA_AFH_OFFSETS_BINDING", b.offsets},
            {"PENUMBRA_AFH_POSITIONS_BINDING", b.positions}, {"PENUMBRA_AFH_SHADOW_BINDING", b.shadow},
            {"PENUMBRA_AFH_WORK_BINDING", b.work}, {"PENUMBRA_AFH_HEADER_BINDING", b.header},
            {"PENUMBRA_AFH_SLOTS_BINDING", b.slots}, {"PENUMBRA_AFH_TEXELS_BINDING", b.texels},
            {"PENUMBRA_AFH_STATES_BINDING", b.states}, {"PENUMBRA_AFH_SPILL_BINDING", b.spill},
            {"PENUMBRA_AFH_SPILL_WORLD_BINDING", b.spill_world}, {"PENUMBRA_AFH_CASTER_POSITIONS_BINDING", b.caster_positions},
            {"PENUMBRA_AFH_CASTER_INDICES_BINDING", b.caster_indices}, {"PENUMBRA_AFH_TRIANGLES_BINDING", b.triangles},
            {"PENUMBRA_AFH_ITEMS_BINDING", b.items}, {"PENUMBRA_AFH_ARGS_BINDING", b.args}};
        for (const auto& d : binding_defines) defines.push_back({d.first, std::to_string(d.second)});
        conservative_params_ = gl::Buffer(sizeof(ConservativeRasterParams), &conservative_.params, GL_DYNAMIC_STORAGE_BIT);
        ubo_alignment_ = static_cast<uint32_t>(gl::getInteger(GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT));
        param_stride_ = static_cast<uint32_t>(detail::divUp(sizeof(AfhParams), ubo_alignment_) * ubo_alignment_);
        params_staging_.assign(size_t(param_stride_) * paramSlots(), 0u);
        afh_params_ = gl::Buffer(params_staging_.size(), nullptr, GL_DYNAMIC_STORAGE_BIT);
        work_ = gl::Buffer(PENUMBRA_AFH_WORK_WORDS * 4);
        lists_.frustum = gl::Buffer(sizeof(SampleListsFrustum));
        resolve_ = gl::buildComputeProgram("penumbra/alias_free_hard/resolve.comp.glsl", defines, library);
        if (options_.light_pass == AfhLightPass::Compute) {
            buildCompute(defines, library);
        } else {
            buildRaster(defines, library);
        }
        gl::checkErrors("penumbra::AliasFreeHardShadows");
    }
    AliasFreeHardShadows(AliasFreeHardShadows&&) noexcept = default;
    AliasFreeHardShadows& operator=(AliasFreeHardShadows&&) noexcept = default;
    AliasFreeHardShadows(const AliasFreeHardShadows&) = delete;
    AliasFreeHardShadows& operator=(const AliasFreeHardShadows&) = delete;

private:
    /// AfhLightPass::Raster: the light pass's vertex / geometry / fragment programs, the predicate
    /// and occupancy programs, the stencil, framebuffer and queries.
    void buildRaster(ShaderDefines defines, const ShaderLibrary& library) {
        const AfhBindings& b = bindings_;
        const std::vector<std::string> light_stages = {"penumbra/alias_free_hard/light_pass.vert.glsl",
                                                       "penumbra/alias_free_hard/light_pass.geom.glsl",
                                                       "penumbra/alias_free_hard/light_pass.frag.glsl"};
        two_pass_ = afhTwoPass(options_);
        // The geometry stage's storage blocks: work counters, and two-pass the spill + spill-world
        // buffers (GL only requires 0 geometry-stage storage blocks; desktop drivers have 8..16).
        const GLint geometry_blocks_needed = (options_.count_work ? 1 : 0) + (two_pass_ ? 2 : 0);
        if (geometry_blocks_needed > 0) {
            const GLint geometry_blocks = gl::getInteger(GL_MAX_GEOMETRY_SHADER_STORAGE_BLOCKS);
            PENUMBRA_CHECK(geometry_blocks >= geometry_blocks_needed,
                           "penumbra::AliasFreeHardShadows: GL_MAX_GEOMETRY_SHADER_STORAGE_BLOCKS = ", geometry_blocks,
                           ", the light pass's geometry stage needs ", geometry_blocks_needed,
                           two_pass_ ? " (Fixed-6 two-pass: set fixed6_two_pass = false or use ConservativeVariant::Exact)"
                                     : " (count_work)");
        }
        if (two_pass_) {
            // Direct pass at the seed's 6 output vertices, spill pass at 13 (penumbra/conservative_raster).
            ShaderDefines direct = defines, spill = defines;
            direct.push_back({"PENUMBRA_CONSERVATIVE_DIRECT", "1"});
            spill.push_back({"PENUMBRA_CONSERVATIVE_SPILL_DRAW", "1"});
            light_pass_ = gl::buildProgram(light_stages, direct, library);
            spill_pass_ = gl::buildProgram(light_stages, spill, library);
            spill_ = gl::Buffer(static_cast<size_t>(conservative_.spill.buffer_bytes));
            spill_world_ = gl::Buffer(static_cast<size_t>(afhSpillWorldBytes(conservative_.spill.capacity)));
            gl::validateConservativeSpill(conservative_, spillRange());
            spill_bindings_.params = PENUMBRA_CONSERVATIVE_PARAMS_BINDING;
            spill_bindings_.spill = b.spill;
        } else {
            light_pass_ = gl::buildProgram(light_stages, defines, library);
        }
        blocks_ = gl::buildProgram({"penumbra/alias_free_hard/blocks.vert.glsl", "penumbra/alias_free_hard/blocks.frag.glsl"},
                                   defines, library);
        if (options_.skip_empty_texels) {
            occupancy_ = gl::buildProgram({"penumbra/common/fullscreen.vert.glsl", "penumbra/alias_free_hard/occupancy.frag.glsl"},
                                          defines, library);
            stencil_ = gl::Renderbuffer::create();
            glNamedRenderbufferStorage(stencil_.id(), GL_STENCIL_INDEX8, static_cast<GLsizei>(options_.grid_width),
                                       static_cast<GLsizei>(options_.grid_height));
        }
        framebuffer_ = gl::Framebuffer::create();
        glNamedFramebufferParameteri(framebuffer_.id(), GL_FRAMEBUFFER_DEFAULT_WIDTH, static_cast<GLint>(options_.grid_width));
        glNamedFramebufferParameteri(framebuffer_.id(), GL_FRAMEBUFFER_DEFAULT_HEIGHT, static_cast<GLint>(options_.grid_height));
        if (options_.skip_empty_texels) {
            glNamedFramebufferRenderbuffer(framebuffer_.id(), GL_STENCIL_ATTACHMENT, GL_RENDERBUFFER, stencil_.id());
            const GLenum complete = glCheckNamedFramebufferStatus(framebuffer_.id(), GL_DRAW_FRAMEBUFFER);
            PENUMBRA_CHECK(complete == GL_FRAMEBUFFER_COMPLETE, "penumbra::AliasFreeHardShadows: the light pass's ",
                           options_.grid_width, " x ", options_.grid_height,
                           " framebuffer with a GL_STENCIL_INDEX8 attachment (skip_empty_texels) is incomplete (status 0x",
                           std::hex, complete, std::dec, "); set skip_empty_texels = false");
        }
        empty_vao_ = gl::VertexArray::create();
        for (uint32_t q = 0; q < options_.max_list_blocks; ++q) block_queries_.push_back(gl::OcclusionQuery::create());
    }

    /// AfhLightPass::Compute: the setup, args and tiles programs, the chunk's records, scan and
    /// arguments, and a scanner; nothing of the graphics pipeline.
    void buildCompute(ShaderDefines defines, const ShaderLibrary& library) {
        const AfhBindings& b = bindings_;
        const std::pair<const char*, uint32_t> storage[] = {
            {"counts", b.counts}, {"offsets", b.offsets}, {"positions", b.positions}, {"shadow", b.shadow}, {"work", b.work},
            {"caster_positions", b.caster_positions}, {"caster_indices", b.caster_indices}, {"triangles", b.triangles},
            {"items", b.items}, {"args", b.args}};
        // The tiles pass binds the first five with triangles and items, the setup the work counters
        // with the last five: all must be distinct and below the driver's limits (GL's minimum is 8
        // storage bindings; the defaults reach 12).
        const GLint max_storage = gl::getInteger(GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS);
        for (size_t i = 0; i < std::size(storage); ++i) {
            PENUMBRA_CHECK(storage[i].second < static_cast<uint32_t>(std::max<GLint>(max_storage, 0)),
                           "penumbra::AliasFreeHardShadows: AfhBindings::", storage[i].first, " = ", storage[i].second,
                           " is not below GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS = ", max_storage);
            for (size_t j = 0; j < i; ++j)
                PENUMBRA_CHECK(storage[i].second != storage[j].second, "penumbra::AliasFreeHardShadows: AfhBindings::",
                               storage[i].first, " and ", storage[j].first, " are both ", storage[i].second,
                               " (the compute light pass binds them together)");
        }
        const GLint compute_blocks = gl::getInteger(GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS);
        PENUMBRA_CHECK(compute_blocks >= 7, "penumbra::AliasFreeHardShadows: the compute light pass's tiles program uses 7 storage "
                                            "blocks; GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS = ", compute_blocks);
        setup_program_ = gl::buildComputeProgram("penumbra/alias_free_hard/light_pass_setup.comp.glsl", defines, library);
        tiles_ = gl::buildComputeProgram("penumbra/alias_free_hard/light_pass_tiles.comp.glsl", defines, library);
        defines.push_back({"PENUMBRA_AFH_TILES_ARGS", "1"});
        tiles_args_ = gl::buildComputeProgram("penumbra/alias_free_hard/light_pass_tiles.comp.glsl", defines, library);
        chunk_ = afhComputeChunk(options_);
        items_per_group_ = afhComputeItemsPerGroup(options_);
        triangles_ = gl::Buffer(size_t(chunk_) * PENUMBRA_AFH_TRIANGLE_WORDS * 4);
        items_ = gl::Buffer(size_t(chunk_) * 4);
        args_ = gl::Buffer(PENUMBRA_AFH_ARGS_WORDS * 4);
        dummy_ = gl::Buffer(16);
        scanner_.emplace(ScanOptions{}, library);
        scanner_->reserve(chunk_);
        ssbo_alignment_ = static_cast<uint32_t>(gl::getInteger(GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT));
    }

public:

    const AliasFreeHardOptions& options() const { return options_; }

    /// Load time: buffers for up to `max_samples` view samples (lists, shadow bits, states) and the
    /// builder's scan scratch. Throws penumbra::Error when the count is out of range or GL cannot
    /// allocate.
    void reserve(uint32_t max_samples) {
        const SampleListsSetup s = sampleListsSetup(options_.grid_width, options_.grid_height, max_samples);
        builder_.reserve(s);
        if (!lists_.reserve(s, max_samples)) return;
        const size_t samples = lists_.samples;
        shadow_ = gl::Buffer(std::max<size_t>(shadowBitsBytes(samples, 1), 4));
        states_ = gl::Buffer(samples * 4);
        reserved_ = lists_.samples;
        gl::checkErrors("penumbra::AliasFreeHardShadows::reserve");
    }

    /// Load-time checks of the integrator's inputs (GL queries; throws naming the object).
    void validate(const SampleBufferInput& input, uint32_t sample_count, const BufferRange& states = {}) const {
        const SampleListsSetup s = sampleListsSetup(options_.grid_width, options_.grid_height, sample_count);
        builder_.validate(s, input, buffers(), listOptions());
        if (!states.empty()) gl::validateRange(states, uint64_t(sample_count) * 4, "states", "AliasFreeHardShadows::validate");
    }
    void validate(const SampleDepthInput& input, const BufferRange& states = {}) const {
        const uint32_t n = input.view.width * input.view.height;
        const SampleListsSetup s = sampleListsSetup(options_.grid_width, options_.grid_height, n);
        builder_.validate(s, input, buffers(), listOptions());
        if (!states.empty()) gl::validateRange(states, uint64_t(n) * 4, "states", "AliasFreeHardShadows::validate");
    }

    /// Every pass for buffer input (see the summary). `light.view_projection` must see all samples
    /// that should be tested (others come out PENUMBRA_AFH_UNTESTED). `states`: where the per-sample
    /// states go (uint[sample_count]); empty = states().
    Status run(const SampleBufferInput& input, uint32_t sample_count, const SampleListsLight& light,
               const DrawCasters& draw_casters, const BufferRange& states = {}) {
        if (options_.light_pass != AfhLightPass::Raster || !draw_casters) return fail(Status::InvalidArgument);
        return runAny(input, sample_count, light, states, [&] { rasterLightPass(draw_casters); });
    }

    /// Every pass for depth input (sample count = view width * height; sample id = y * width + x).
    Status run(const SampleDepthInput& input, const SampleListsLight& light, const DrawCasters& draw_casters,
               const BufferRange& states = {}) {
        if (options_.light_pass != AfhLightPass::Raster || !draw_casters) return fail(Status::InvalidArgument);
        const uint64_t n = uint64_t(input.view.width) * input.view.height;
        if (n > reserved_) return fail(Status::NotReserved);
        return runAny(input, static_cast<uint32_t>(n), light, states, [&] { rasterLightPass(draw_casters); });
    }

    /// AfhLightPass::Compute, buffer input: every pass, the casters as `caster_count` ranges
    /// (CasterBuffer; ranges of 0 triangles are skipped). Misuse (the Raster light pass, a stride
    /// below 12 or not a multiple of 4, a range too small for its triangles, a misaligned offset)
    /// returns a Status and does nothing.
    Status run(const SampleBufferInput& input, uint32_t sample_count, const SampleListsLight& light, const CasterBuffer* casters,
               uint32_t caster_count, const BufferRange& states = {}) {
        const Status c = checkCasters(casters, caster_count);
        if (c != Status::Ok) return c;
        return runAny(input, sample_count, light, states, [&] { computeLightPass(casters, caster_count); });
    }

    /// AfhLightPass::Compute, depth input.
    Status run(const SampleDepthInput& input, const SampleListsLight& light, const CasterBuffer* casters, uint32_t caster_count,
               const BufferRange& states = {}) {
        const Status c = checkCasters(casters, caster_count);
        if (c != Status::Ok) return c;
        const uint64_t n = uint64_t(input.view.width) * input.view.height;
        if (n > reserved_) return fail(Status::NotReserved);
        return runAny(input, static_cast<uint32_t>(n), light, states, [&] { computeLightPass(casters, caster_count); });
    }

    /// Load-time check of CasterBuffer ranges against their buffers (GL queries; throws naming the
    /// range): what run() checks, plus the buffers' sizes.
    void validateCasters(const CasterBuffer* casters, uint32_t caster_count) const {
        const char* f = "AliasFreeHardShadows::validateCasters";
        PENUMBRA_CHECK(options_.light_pass == AfhLightPass::Compute, "penumbra::", f,
                       ": casters as buffers need options.light_pass = AfhLightPass::Compute");
        gl::validateCasterBuffers(casters, caster_count, ssbo_alignment_, f);
    }

    /// What the last run did: fit, statistics, passes, overflow, work counters (reads back and
    /// waits for the GPU — for tools, tests and benchmarks, not for frames).
    AliasFreeHardFrame readFrame() const {
        AliasFreeHardFrame f;
        const SampleListsBuffers b = buffers();
        const SampleListsFrustum frustum = SampleListBuilder::readFrustum(b.frustum);
        f.fit = lightFrustumFitFromFrustum(frustum);
        f.fit.keys = SampleListBuilder::readHeader(b.header);
        f.light_view_projection = frustum.view_projection;
        f.statistics = SampleListBuilder::readStatistics(setup_, b);
        f.passes = static_cast<uint32_t>(
            std::min<uint64_t>(detail::divUp(f.statistics.max_list_length, options_.list_block), options_.max_list_blocks));
        const std::vector<uint32_t> work = work_.download<uint32_t>(0, PENUMBRA_AFH_WORK_WORDS);
        f.overflow = work[PENUMBRA_AFH_WORK_OVERFLOW];
        f.fragments = work[PENUMBRA_AFH_WORK_FRAGMENTS];
        f.tests = work[PENUMBRA_AFH_WORK_TESTS];
        f.triangles_emitted = work[PENUMBRA_AFH_WORK_TRIANGLES];
        f.fallbacks = work[PENUMBRA_AFH_WORK_FALLBACKS];
        f.tests_skipped = work[PENUMBRA_AFH_WORK_TESTS_SKIPPED];
        f.fragments_skipped = work[PENUMBRA_AFH_WORK_FRAGMENTS_SKIPPED];
        f.triangles_culled = work[PENUMBRA_AFH_WORK_TRIANGLES_CULLED];
        f.spill_overflow = work[PENUMBRA_AFH_WORK_SPILL_OVERFLOW];
        f.spilled = work[PENUMBRA_AFH_WORK_SPILL_COUNT] / 3u + f.spill_overflow;
        if (options_.light_pass == AfhLightPass::Compute) {
            // The compute pass computes every block's box in one setup and never spills.
            f.spilled = f.spill_overflow = 0;
            f.chunks = chunks_;
            f.items = work[PENUMBRA_AFH_WORK_ITEMS];
            f.caster_indices_out_of_range = work[PENUMBRA_AFH_WORK_CASTER_INDICES_OUT_OF_RANGE];
        }
        return f;
    }

    /// uint per view-sample id: PENUMBRA_AFH_* states (when run() was given no range).
    const gl::Buffer& stateBuffer() const { return states_; }
    BufferRange states() const { return {states_.id(), 0, states_.size()}; }
    /// The lists of the last run (positions, ids, slots ... see SampleListsBuffers).
    SampleListsBuffers buffers() const { return lists_.ranges(); }
    const SampleListsSetup& setup() const { return setup_; }
    const gl::Buffer& shadowBits() const { return shadow_; }
    uint32_t reservedSamples() const { return reserved_; }
    /// The light pass's caster program (two-pass: the direct pass, geometry stage max_vertices 6;
    /// otherwise the single pass, 13) and the spill pass's program (0 unless two-pass). Query
    /// GL_GEOMETRY_VERTICES_OUT on them to see what the geometry stages declare.
    GLuint lightPassProgram() const { return light_pass_.id(); }
    GLuint spillPassProgram() const { return spill_pass_.id(); }
    /// Two-pass: the spill-pass plan the light pass records (capacity, sizes), and its buffer.
    const ConservativeRasterSetup& conservativeSetup() const { return conservative_; }
    bool twoPass() const { return two_pass_; }

private:
    AliasFreeHardOptions options_;
    AfhBindings bindings_;
    SampleListBuilder builder_;
    ConservativeRasterSetup conservative_;
    gl::Program light_pass_, spill_pass_, blocks_, resolve_, occupancy_;
    // AfhLightPass::Compute: programs, the chunk's records, tile counts (scanned) and arguments.
    gl::Program setup_program_, tiles_, tiles_args_;
    gl::Buffer triangles_, items_, args_, dummy_;
    std::optional<Scanner> scanner_;  // compute only: a Scanner compiles its kernels when constructed
    uint32_t chunk_ = 0, chunks_ = 0, items_per_group_ = 1, ssbo_alignment_ = 256;
    gl::Renderbuffer stencil_;  // skip_empty_texels: W x H, non-empty list blocks per texel
    gl::Buffer conservative_params_, afh_params_, work_;
    gl::Buffer spill_, spill_world_;  // two-pass only: spill header + triangles, spill-world header + vertices
    gl::ConservativeRasterBindings spill_bindings_{};
    bool two_pass_ = false;
    SampleListStorage lists_;
    gl::Buffer shadow_, states_;
    gl::Framebuffer framebuffer_;
    gl::VertexArray empty_vao_;
    std::vector<gl::OcclusionQuery> block_queries_;
    std::vector<uint8_t> params_staging_;
    uint32_t ubo_alignment_ = 256, param_stride_ = 256;
    uint32_t reserved_ = 0;
    SampleListsSetup setup_;

    BufferRange spillRange() const { return {spill_.id(), 0, spill_.size()}; }

    static Status fail(Status s) {
        PENUMBRA_ASSERT(s == Status::Ok && "penumbra::AliasFreeHardShadows: per-frame misuse (see the returned Status)");
        return s;
    }

    // Slot 0: predicate and resolve; slot 1 + 2 b + c: block b, caster class c.
    uint32_t paramSlots() const { return 1 + 2 * options_.max_list_blocks; }

    SampleListsOptions listOptions() const {
        SampleListsOptions o;
        o.depth_range = LightDepthRange::Unclipped;
        return o;
    }
    SampleListsBuild listBuild() const {
        SampleListsBuild b;
        b.fit_frustum = options_.fit_frustum;
        b.statistics = true;  // the predicate pass reads max_list_length
        return b;
    }

    /// The per-frame check of the caster ranges (no GL call).
    Status checkCasters(const CasterBuffer* casters, uint32_t count) const {
        if (options_.light_pass != AfhLightPass::Compute) return fail(Status::InvalidArgument);
        const Status s = checkCasterBuffers(casters, count, ssbo_alignment_);
        return s == Status::Ok ? s : fail(s);
    }

    /// run() for either input and either light pass: checks, lists, `light_pass()`, resolve.
    template <class Input, class LightPass>
    Status runAny(const Input& input, uint32_t sample_count, const SampleListsLight& light, const BufferRange& states,
                  const LightPass& light_pass) {
        const Status s = begin(sample_count, light, states);
        if (s != Status::Ok) return s;
        const Status built = builder_.build(setup_, light, input, buffers(), listOptions(), listBuild());
        if (built != Status::Ok) return built;
        beginLightPass(light.light);
        light_pass();
        resolve(states);
        return Status::Ok;
    }

    Status begin(uint32_t sample_count, const SampleListsLight& light, const BufferRange& states) {
        if (reserved_ == 0 || sample_count > reserved_) return fail(Status::NotReserved);
        if (!afhLightValid(light.light)) return fail(Status::InvalidArgument);
        if (light.light.w == 0.0f && !(options_.directional_reach > 0.0f)) return fail(Status::InvalidArgument);
        if (!states.empty() && !states.holds(uint64_t(sample_count) * 4)) return fail(Status::RangeTooSmall);
        // sample_count <= reserved_, which reserve() validated: sampleListsSetup cannot throw here.
        setup_ = sampleListsSetup(options_.grid_width, options_.grid_height, sample_count);
        return Status::Ok;
    }

    void writeParams(const glm::vec4& light) {
        auto put = [&](uint32_t slot, const AfhParams& p) {
            std::memcpy(params_staging_.data() + size_t(slot) * param_stride_, &p, sizeof p);
        };
        put(0, afhParams(options_, light, 0, 0u, setup_.sample_count));
        for (uint32_t b = 0; b < options_.max_list_blocks; ++b) {
            for (uint32_t c = 0; c < 2; ++c) {
                // c == 0: closed casters
                const uint32_t flags = c != 0                     ? 0u
                                       : options_.back_faces_only   ? PENUMBRA_AFH_FLAG_CLOSED
                                       : options_.light_facing_only ? PENUMBRA_AFH_FLAG_CLOSED_LIGHT_FACING
                                                                    : 0u;
                put(1 + 2 * b + c, afhParams(options_, light, b, flags, setup_.sample_count));
            }
        }
        glNamedBufferSubData(afh_params_.id(), 0, static_cast<GLsizeiptr>(params_staging_.size()), params_staging_.data());
    }

    void bindParams(uint32_t slot) const {
        gl::bindRange(GL_UNIFORM_BUFFER, bindings_.params, afh_params_.id(),
                      static_cast<GLintptr>(size_t(slot) * param_stride_), sizeof(AfhParams));
    }

    /// Parameters, cleared shadow bits and work counters.
    void beginLightPass(const glm::vec4& light) {
        writeParams(light);
        const uint32_t zero = 0;
        const uint64_t shadow_bytes = std::max<uint64_t>(shadowBitsBytes(std::max<uint32_t>(setup_.sample_count, 1), 1), 4);
        glClearNamedBufferSubData(shadow_.id(), GL_R32UI, 0, static_cast<GLsizeiptr>(shadow_bytes), GL_RED_INTEGER,
                                  GL_UNSIGNED_INT, &zero);
        glClearNamedBufferSubData(work_.id(), GL_R32UI, 0, PENUMBRA_AFH_WORK_WORDS * 4, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }

    /// AfhLightPass::Compute: per chunk of caster triangles (both classes; the class picks the
    /// setup's parameter slot, whose flags carry the closed casters' cull), the setup of every
    /// range piece in the chunk, the inclusive scan of their tile counts, the args program, then
    /// per list block one indirect tiles pass (0 groups past the longest list).
    void computeLightPass(const CasterBuffer* casters, uint32_t caster_count) {
        chunks_ = 0;
        const GLuint setup_id = setup_program_.id();
        uint32_t filled = 0;  // records of the chunk being set up
        const auto flush = [&] {
            if (filled == 0) return;
            ++chunks_;
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            const BufferRange items{items_.id(), 0, uint64_t(filled) * 4};
            scanner_->inclusive(items, items, filled);  // reserved for the chunk: cannot fail
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.items, items_.id());
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.work, work_.id());
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.args, args_.id());
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.header, lists_.header.id(), 0, sizeof(SampleListsHeader));
            tiles_args_.use();
            glProgramUniform1ui(tiles_args_.id(), 0, filled);
            glProgramUniform2ui(tiles_args_.id(), 1, options_.list_block, options_.max_list_blocks);
            glProgramUniform1ui(tiles_args_.id(), 2, items_per_group_);
            glDispatchCompute(1, 1, 1);
            glMemoryBarrier(GL_COMMAND_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
            tiles_.use();
            glProgramUniform1ui(tiles_.id(), 0, filled);
            glProgramUniform1ui(tiles_.id(), 1, items_per_group_);
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.counts, lists_.counts.id());
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.offsets, lists_.offsets.id());
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.positions, lists_.positions.id());
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.shadow, shadow_.id());
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.triangles, triangles_.id());
            glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, args_.id());
            for (uint32_t b = 0; b < options_.max_list_blocks; ++b) {
                bindParams(1 + 2 * b + 1);  // pass.x = b
                glDispatchComputeIndirect(static_cast<GLintptr>(size_t(b) * 16));
            }
            // The next chunk's setup rewrites the records and counts the tiles passes read.
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            filled = 0;
        };
        for (uint32_t c = 0; c < 2; ++c) {
            const CasterClass cls = c == 0 ? CasterClass::Closed : CasterClass::Open;
            for (uint32_t i = 0; i < caster_count; ++i) {
                const CasterBuffer& range = casters[i];
                if (range.triangles == 0 || range.caster_class != cls) continue;
                for (uint32_t first = 0; first < range.triangles;) {
                    if (filled == chunk_) flush();
                    const uint32_t n = std::min(chunk_ - filled, range.triangles - first);
                    setup_program_.use();
                    // Every binding again: the scanner of the previous chunk rebinds some.
                    bindParams(1 + c);  // block 0, this class's flags
                    gl::bindBase(GL_UNIFORM_BUFFER, PENUMBRA_CONSERVATIVE_PARAMS_BINDING, conservative_params_.id());
                    gl::bindRange(GL_UNIFORM_BUFFER, bindings_.frustum, lists_.frustum.id(), 0, sizeof(SampleListsFrustum));
                    gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.caster_positions, range.positions);
                    if (range.indices.empty()) {
                        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.caster_indices, dummy_.id());
                    } else {
                        gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.caster_indices, range.indices);
                    }
                    gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.triangles, triangles_.id());
                    gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.items, items_.id());
                    gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.work, work_.id());
                    glProgramUniform4ui(setup_id, 0, first, n, range.stride / 4, range.indices.empty() ? 0u : 1u);
                    glProgramUniform1ui(setup_id, 1, static_cast<GLuint>(std::min<uint64_t>(range.positions.size / 4, 0xFFFFFFFFu)));
                    glProgramUniform1ui(setup_id, 2, filled);
                    glDispatchCompute(static_cast<GLuint>(detail::divUp(n, PENUMBRA_AFH_SETUP_GROUP)), 1, 1);
                    filled += n;
                    first += n;
                }
            }
        }
        flush();
    }

    /// AfhLightPass::Raster: predicates, occupancy stencil, the casters drawn per list block.
    void rasterLightPass(const DrawCasters& draw_casters) {
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, framebuffer_.id());
        glViewport(0, 0, static_cast<GLsizei>(options_.grid_width), static_cast<GLsizei>(options_.grid_height));
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        glDisable(GL_RASTERIZER_DISCARD);
        glEnable(GL_DEPTH_CLAMP);  // casters nearer than the near plane or beyond the far plane still cast
        glDisable(GL_STENCIL_TEST);  // the framebuffer may hold the occupancy stencil: its own state comes at (3b)
        gl::setPassRasterState();
        // (3) Which list blocks does the longest list need? One point per block, on the GPU.
        blocks_.use();
        glBindVertexArray(empty_vao_.id());
        bindParams(0);
        gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.header, lists_.header.id(), 0, sizeof(SampleListsHeader));
        gl::drawListBlockPredicates(block_queries_, options_.max_list_blocks, options_.grid_width, options_.grid_height);
        // (3b) skip_empty_texels: the stencil counts each texel's non-empty list blocks.
        const bool stencil = options_.skip_empty_texels;
        if (stencil) {
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.counts, lists_.counts.id());
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.offsets, lists_.offsets.id());
            gl::drawOccupancyStencil(framebuffer_.id(), occupancy_.id(), empty_vao_.id(), block_queries_, options_.max_list_blocks,
                                     [&](uint32_t b) { bindParams(1 + 2 * b + 1); });
        }
        // (4) Light pass, block by block; blocks no list needs are skipped by the GPU. With the
        // stencil, block b's fragments are shaded where b < the texel's non-empty blocks (early
        // fragment tests).
        light_pass_.use();
        gl::bindBase(GL_UNIFORM_BUFFER, PENUMBRA_CONSERVATIVE_PARAMS_BINDING, conservative_params_.id());
        gl::bindRange(GL_UNIFORM_BUFFER, bindings_.frustum, lists_.frustum.id(), 0, sizeof(SampleListsFrustum));
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.counts, lists_.counts.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.offsets, lists_.offsets.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.positions, lists_.positions.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.shadow, shadow_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.work, work_.id());
        static constexpr shared::PenumbraAfhSpillWorldHeader kSpillWorldReset{};
        const BufferRange spill = spillRange();
        for (uint32_t b = 0; b < options_.max_list_blocks; ++b) {
            gl::occupancyStencilTest(stencil, b, GL_LESS);
            glBeginConditionalRender(block_queries_[b].id(), GL_QUERY_WAIT);
            if (two_pass_) {
                // Buffer updates run whether or not the block is drawn; they only reset.
                gl::beginConservativeSpill(conservative_, spill, spill_bindings_);  // validated at construction
                glNamedBufferSubData(spill_world_.id(), 0, sizeof kSpillWorldReset, &kSpillWorldReset);
                gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.spill_world, spill_world_.id());
            }
            for (uint32_t c = 0; c < 2; ++c) {
                bindParams(1 + 2 * b + c);
                light_pass_.use();
                draw_casters(c == 0 ? CasterClass::Closed : CasterClass::Open);
            }
            if (two_pass_) {
                // One spill draw for both classes: culling happened in the direct pass, and the
                // fragment stage reads no class flag, so block b's open-class slot serves both.
                spill_pass_.use();
                bindParams(1 + 2 * b + 1);
                glBindVertexArray(empty_vao_.id());
                gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.spill_world, spill_world_.id());
                gl::drawConservativeSpill(conservative_, spill, spill_bindings_);
            }
            glEndConditionalRender();
            // Later blocks read the bits earlier ones wrote (the skip of shadowed samples); the
            // next block's spill reset and the copy below follow the appends.
            glMemoryBarrier(two_pass_ ? GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT
                                      : GL_SHADER_STORAGE_BARRIER_BIT);
            if (two_pass_ && b == 0) {
                // Block 0's spill figures for readFrame(), on the GPU (every block spills the same
                // triangles; a skipped block 0 leaves the reset header: nothing spilled).
                glCopyNamedBufferSubData(spill_.id(), work_.id(), offsetof(ConservativeSpillHeader, count),
                                         PENUMBRA_AFH_WORK_SPILL_COUNT * 4, 4);
                glCopyNamedBufferSubData(spill_.id(), work_.id(), offsetof(ConservativeSpillHeader, overflow),
                                         PENUMBRA_AFH_WORK_SPILL_OVERFLOW * 4, 4);
            }
        }
        glDisable(GL_STENCIL_TEST);
    }

    /// (5) Resolve.
    void resolve(const BufferRange& states) {
        resolve_.use();
        bindParams(0);
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.slots, lists_.slots.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.texels, lists_.texels.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.shadow, shadow_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.offsets, lists_.offsets.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.work, work_.id());
        if (states.empty()) {
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.states, states_.id());
        } else {
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.states, states);
        }
        const detail::DispatchGrid grid = detail::foldDispatch(detail::divUp(setup_.sample_count, 256));
        if (grid.groups) glDispatchCompute(grid.x, grid.y, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    }
};

}  // namespace penumbra

#endif
