// penumbra — the GL executor of the view-sample list builder (sintorn2008 §3.1, §4.3, Fig. 9).
// Pure setup, the rules and the CPU twin are in penumbra/sample_lists.hpp (no GL needed).
//
// Integration summary
//   needs:    a GL 4.5 context (compute shaders, SSBOs, fp64 for the GPU fit); PENUMBRA_GL_HEADER
//             (see gl/gl.hpp); the scan block; shaders from the embedded table or a ShaderLibrary.
//   setup:    SampleListBuilder(library, scan options, bindings, extra defines) compiles every
//             kernel; reserve(setup) sizes the scanner and must precede build() for that grid;
//             validate(...) checks the integrator's ranges and textures against GL once (queries).
//   per frame: build(setup, light, input, buffers, options, build) — count → scan → scatter, with
//             the §4.3 fit on the GPU first when build.fit_frustum is set (fit.comp.glsl reduces
//             keys into the header, fit_resolve.comp.glsl writes the cropped frustum into
//             buffers.frustum, which the count pass reads as a uniform block — nothing travels
//             through the CPU) and the Fig. 9 statistics after when build.statistics is set.
//             It allocates nothing, queries nothing, reads nothing back and throws nothing; a
//             range too small or misaligned, a grid larger than reserved or invalid light/view
//             numbers return a Status other than Ok (after PENUMBRA_ASSERT) before any GL call.
//   read-back (explicit, waits for the GPU; tests and tools): readHeader, readFrustum,
//             readStatistics, downloadSampleLists.
//
// GL state contract of build()/fit()/statistics(): changes, without restoring, the current
// program, the uniform-buffer bindings SampleListsBindings::params and ::frustum, the SSBO
// bindings the passes use (SampleListsBindings; ScanBindings of the scanner), and for the depth
// input the texture units ::depth_unit / ::normal_unit with the builder's own sampler object
// (compare mode off, nearest) bound there. Nothing else: no unbinding, no glUseProgram(0), no
// error draining. Barriers: GL_SHADER_STORAGE_BARRIER_BIT (| GL_UNIFORM_BARRIER_BIT after the
// fit) between passes, and before returning GL_SHADER_STORAGE_BARRIER_BIT |
// GL_UNIFORM_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT, so the
// integrator's shaders read the lists as SSBOs and the frustum as a uniform block, indirect
// commands may read the header, and the host may read anything back. Inputs written by shaders
// need the caller's barrier first; a depth texture rendered through a framebuffer needs none.
// Depth input textures: GL_TEXTURE_2D, level 0 read with texelFetch; bit-exact CPU agreement
// needs GL_DEPTH_COMPONENT32F (or the values read back).
#ifndef PENUMBRA_GL_SAMPLE_LISTS_HPP
#define PENUMBRA_GL_SAMPLE_LISTS_HPP

#include "penumbra/buffer_range.hpp"
#include "penumbra/gl/gl.hpp"
#include "penumbra/gl/objects.hpp"
#include "penumbra/gl/scan.hpp"
#include "penumbra/gl/shader.hpp"
#include "penumbra/gl/validate.hpp"
#include "penumbra/sample_lists.hpp"

#include <algorithm>
#include <string>
#include <utility>

namespace penumbra {

/// Binding points of the builder's kernels; value-initialised = the sample_lists_shared.h defaults.
struct SampleListsBindings {
    uint32_t params = PENUMBRA_SAMPLE_LISTS_BINDING_PARAMS;    ///< uniform block
    uint32_t frustum = PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM;  ///< uniform block (count pass)
    uint32_t positions = PENUMBRA_SAMPLE_LISTS_BINDING_POSITIONS;  ///< SSBOs from here on
    uint32_t normals = PENUMBRA_SAMPLE_LISTS_BINDING_NORMALS;
    uint32_t counts = PENUMBRA_SAMPLE_LISTS_BINDING_COUNTS;
    uint32_t frustum_out = PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM_OUT;
    uint32_t offsets = PENUMBRA_SAMPLE_LISTS_BINDING_OFFSETS;
    uint32_t header = PENUMBRA_SAMPLE_LISTS_BINDING_HEADER;
    uint32_t list_positions = PENUMBRA_SAMPLE_LISTS_BINDING_LIST_POSITIONS;
    uint32_t list_ids = PENUMBRA_SAMPLE_LISTS_BINDING_LIST_IDS;
    uint32_t sample_slots = PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_SLOTS;
    uint32_t sample_texels = PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_TEXELS;
    uint32_t depth_unit = PENUMBRA_SAMPLE_LISTS_UNIT_DEPTH;    ///< texture units (depth input)
    uint32_t normal_unit = PENUMBRA_SAMPLE_LISTS_UNIT_NORMALS;
    ScanBindings scan{};  ///< the scanner's pass 2 bindings
};

/// View samples from buffers the caller owns.
struct SampleBufferInput {
    BufferRange positions;  ///< vec4[sample_count]: xyz world position; w == 0 = no sample
    BufferRange normals;    ///< vec4[sample_count]: xyz world normal; may be empty when culling is off
};

/// View samples from the view's depth buffer (GL_TEXTURE_2D objects the caller owns).
struct SampleDepthInput {
    GLuint depth_texture = 0;   ///< window depth at level 0 (1.0 = background)
    GLuint normal_texture = 0;  ///< xyz world normal at level 0; 0 allowed when culling is off
    SampleListsView view;
};

/// The ranges a build writes (sizes: SampleListsSetup::*_bytes; frustum: sizeof(SampleListsFrustum)).
struct SampleListsBuffers {
    BufferRange counts;          ///< uint[W*H]
    BufferRange offsets;         ///< uint[W*H]
    BufferRange list_positions;  ///< vec4[sample_count]
    BufferRange list_ids;        ///< uint[sample_count]
    BufferRange sample_slots;    ///< uint[sample_count]
    BufferRange sample_texels;   ///< uint[sample_count]
    BufferRange header;          ///< SampleListsHeader
    BufferRange frustum;         ///< SampleListsFrustum: read by the count pass (and your light pass)
};

/// Per-build switches of the executor. Value-initialised = lists only, the light's own frustum.
struct SampleListsBuild {
    bool fit_frustum = false;  ///< §4.3 on the GPU before the lists (writes buffers.frustum)
    LightFrustumFitOptions fit;
    bool statistics = false;   ///< Fig. 9 words of the header after the lists
};

namespace detail {

inline void clearWords(const BufferRange& range, uint32_t first_word, uint32_t words, uint32_t value) {
    if (words == 0) return;
    glClearNamedBufferSubData(range.buffer, GL_R32UI, static_cast<GLintptr>(range.offset + uint64_t(first_word) * 4),
                              static_cast<GLsizeiptr>(uint64_t(words) * 4), GL_RED_INTEGER, GL_UNSIGNED_INT, &value);
}

inline void dispatch(const DispatchGrid& grid) {
    if (grid.groups) glDispatchCompute(grid.x, grid.y, 1);
}

inline void validateTexture(GLuint id, const SampleListsView& view, const char* what, const char* function) {
    PENUMBRA_CHECK(id != 0 && glIsTexture(id), "penumbra::", function, ": ", what, " (", id,
                   ") is not a texture object");
    GLint target = 0, width = 0, height = 0;
    glGetTextureParameteriv(id, GL_TEXTURE_TARGET, &target);
    PENUMBRA_CHECK(target == GL_TEXTURE_2D, "penumbra::", function, ": ", what, " (", id, ") is not a GL_TEXTURE_2D");
    glGetTextureLevelParameteriv(id, 0, GL_TEXTURE_WIDTH, &width);
    glGetTextureLevelParameteriv(id, 0, GL_TEXTURE_HEIGHT, &height);
    PENUMBRA_CHECK(width >= 0 && height >= 0 && uint32_t(width) >= view.width && uint32_t(height) >= view.height,
                   "penumbra::", function, ": ", what, " (", id, ") is ", width, " x ", height, ", the view is ",
                   view.width, " x ", view.height);
}

}  // namespace detail

/// Builds the lists on the GPU. Owns its programs, a 256-byte uniform buffer, a sampler object and
/// the Scanner (with its scratch); movable, not copyable. `library` must outlive construction only.
class SampleListBuilder {
public:
    explicit SampleListBuilder(const ShaderLibrary& library = ShaderLibrary::embedded(), const ScanOptions& scan = {},
                               const SampleListsBindings& bindings = {}, const ShaderDefines& extra_defines = {})
        : bindings_(bindings), scanner_(scan, library, bindings.scan) {
        for (int kernel = 0; kernel < kKernels; ++kernel) {
            const bool per_input = kernel == kCount || kernel == kScatter || kernel == kFit;
            for (int input = 0; input < (per_input ? 2 : 1); ++input) {
                programs_[kernel][input] = buildKernel(Kernel(kernel), input, library, extra_defines);
            }
        }
        params_ = gl::Buffer(sizeof(SampleListsParams), nullptr, GL_DYNAMIC_STORAGE_BIT);
        glCreateSamplers(1, &sampler_);
        glSamplerParameteri(sampler_, GL_TEXTURE_COMPARE_MODE, GL_NONE);
        glSamplerParameteri(sampler_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glSamplerParameteri(sampler_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        ssbo_alignment_ = static_cast<uint32_t>(gl::getInteger(GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT));
        ubo_alignment_ = static_cast<uint32_t>(gl::getInteger(GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT));
    }
    SampleListBuilder(SampleListBuilder&& other) noexcept { *this = std::move(other); }
    SampleListBuilder& operator=(SampleListBuilder&& other) noexcept {
        if (this != &other) {
            release();
            bindings_ = other.bindings_;
            scanner_ = std::move(other.scanner_);
            for (int k = 0; k < kKernels; ++k) {
                for (int i = 0; i < 2; ++i) programs_[k][i] = std::move(other.programs_[k][i]);
            }
            params_ = std::move(other.params_);
            sampler_ = std::exchange(other.sampler_, 0);
            ssbo_alignment_ = other.ssbo_alignment_;
            ubo_alignment_ = other.ubo_alignment_;
            reserved_lists_ = std::exchange(other.reserved_lists_, 0);
        }
        return *this;
    }
    SampleListBuilder(const SampleListBuilder&) = delete;
    SampleListBuilder& operator=(const SampleListBuilder&) = delete;
    ~SampleListBuilder() { release(); }

    /// Bytes of GPU scratch the builder holds for grids of this size (the Scanner's), beyond the
    /// caller's buffers and the 256-byte uniform block.
    size_t scratchBytes(const SampleListsSetup& setup) const { return scanner_.scratchBytes(setup.lists); }

    /// Load-time preparation for grids up to `setup.lists` lists: sizes the scanner. Throws
    /// penumbra::Error when GL cannot allocate.
    void reserve(const SampleListsSetup& setup) {
        scanner_.reserve(setup.lists);
        reserved_lists_ = std::max(reserved_lists_, setup.lists);
    }

    /// Load-time checks of the integrator's objects (GL queries; throws penumbra::Error naming the
    /// object and the size it must have). build() assumes them and only checks sizes it was told.
    void validate(const SampleListsSetup& setup, const SampleBufferInput& input, const SampleListsBuffers& out,
                  const SampleListsOptions& options = {}) const {
        const char* f = "SampleListBuilder::validate";
        gl::validateRange(input.positions, uint64_t(setup.sample_count) * 16, "input positions", f, ssbo_alignment_);
        if (options.cull_back_facing) {
            gl::validateRange(input.normals, uint64_t(setup.sample_count) * 16, "input normals", f, ssbo_alignment_);
        }
        validateOutputs(setup, out);
    }
    void validate(const SampleListsSetup& setup, const SampleDepthInput& input, const SampleListsBuffers& out,
                  const SampleListsOptions& options = {}) const {
        const char* f = "SampleListBuilder::validate";
        detail::validateTexture(input.depth_texture, input.view, "depth texture", f);
        if (options.cull_back_facing) detail::validateTexture(input.normal_texture, input.view, "normal texture", f);
        validateOutputs(setup, out);
    }

    /// Passes 1-3 (and the fit / statistics when asked) for buffer input. Per-frame contract above.
    Status build(const SampleListsSetup& setup, const SampleListsLight& light, const SampleBufferInput& input,
                 const SampleListsBuffers& out, const SampleListsOptions& options = {},
                 const SampleListsBuild& build = {}) {
        Status s = checkBufferInput(setup, input, options);
        if (s == Status::Ok) s = checkOutputs(setup, out, build);
        if (s == Status::Ok && !detail::sampleListsParamsValid(setup, light, nullptr, build.fit)) s = Status::InvalidArgument;
        if (s != Status::Ok) return fail(s);
        run(setup, detail::makeSampleListsParams(setup, light, options, nullptr, build.fit), 0,
            [&] { bindBufferInput(input, options); }, out, build);
        return Status::Ok;
    }

    /// Passes 1-3 for depth input (sample count = view width * height).
    Status build(const SampleListsSetup& setup, const SampleListsLight& light, const SampleDepthInput& input,
                 const SampleListsBuffers& out, const SampleListsOptions& options = {},
                 const SampleListsBuild& build = {}) {
        Status s = checkOutputs(setup, out, build);
        if (s == Status::Ok && (input.depth_texture == 0 || (options.cull_back_facing && input.normal_texture == 0))) {
            s = Status::InvalidArgument;
        }
        if (s == Status::Ok && !detail::sampleListsParamsValid(setup, light, &input.view, build.fit)) {
            s = Status::InvalidArgument;
        }
        if (s != Status::Ok) return fail(s);
        run(setup, detail::makeSampleListsParams(setup, light, options, &input.view, build.fit), 1,
            [&] { bindDepthInput(input, options); }, out, build);
        return Status::Ok;
    }

    /// Fig. 9: reduces counts into the header's statistics words (dispatch only; build() does it
    /// too with SampleListsBuild::statistics).
    Status statistics(const SampleListsSetup& setup, const SampleListsBuffers& lists) {
        if (!lists.counts.holds(setup.counts_bytes) || !lists.header.holds(setup.header_bytes)) {
            return fail(Status::RangeTooSmall);
        }
        SampleListsParams params{};
        params.grid = glm::uvec4(setup.grid_width, setup.grid_height, setup.sample_count, 0u);
        upload(params);
        runStatistics(setup, lists);
        glMemoryBarrier(kEndBarriers);
        return Status::Ok;
    }

    /// Reads the header back (waits for the GPU).
    static SampleListsHeader readHeader(const BufferRange& header) {
        SampleListsHeader h{};
        glGetNamedBufferSubData(header.buffer, static_cast<GLintptr>(header.offset), sizeof h, &h);
        return h;
    }
    /// Reads the frustum block back (waits for the GPU).
    static SampleListsFrustum readFrustum(const BufferRange& frustum) {
        SampleListsFrustum f{};
        glGetNamedBufferSubData(frustum.buffer, static_cast<GLintptr>(frustum.offset), sizeof f, &f);
        return f;
    }
    /// Fig. 9 statistics of a build made with SampleListsBuild::statistics (waits for the GPU).
    static SampleListStatistics readStatistics(const SampleListsSetup& setup, const SampleListsBuffers& lists) {
        return sampleListStatisticsFromHeader(setup, readHeader(lists.header));
    }

    const SampleListsBindings& bindings() const { return bindings_; }
    const Scanner& scanner() const { return scanner_; }
    /// GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT: every SSBO range offset must be a multiple.
    uint32_t storageAlignment() const { return ssbo_alignment_; }

private:
    enum Kernel { kCount, kScatter, kFit, kFitResolve, kStatistics, kKernels };
    static constexpr GLbitfield kEndBarriers = GL_SHADER_STORAGE_BARRIER_BIT | GL_UNIFORM_BARRIER_BIT |
                                               GL_BUFFER_UPDATE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT;

    SampleListsBindings bindings_;
    Scanner scanner_;
    gl::Program programs_[kKernels][2];
    gl::Buffer params_;
    GLuint sampler_ = 0;
    uint32_t ssbo_alignment_ = 256, ubo_alignment_ = 256;
    uint32_t reserved_lists_ = 0;

    void release() {
        if (sampler_) glDeleteSamplers(1, &sampler_);
        sampler_ = 0;
    }

    static Status fail(Status s) {
        PENUMBRA_ASSERT(s == Status::Ok && "penumbra::SampleListBuilder: per-frame misuse (see the returned Status)");
        return s;
    }

    gl::Program buildKernel(Kernel kernel, int input, const ShaderLibrary& library, const ShaderDefines& extra) const {
        static const char* const keys[kKernels] = {
            "penumbra/sample_lists/count.comp.glsl", "penumbra/sample_lists/scatter.comp.glsl",
            "penumbra/sample_lists/fit.comp.glsl", "penumbra/sample_lists/fit_resolve.comp.glsl",
            "penumbra/sample_lists/statistics.comp.glsl"};
        const SampleListsBindings& b = bindings_;
        ShaderDefines defines = {
            {"PENUMBRA_SAMPLE_LISTS_BINDING_PARAMS", std::to_string(b.params)},
            {"PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM", std::to_string(b.frustum)},
            {"PENUMBRA_SAMPLE_LISTS_BINDING_POSITIONS", std::to_string(b.positions)},
            {"PENUMBRA_SAMPLE_LISTS_BINDING_NORMALS", std::to_string(b.normals)},
            {"PENUMBRA_SAMPLE_LISTS_BINDING_COUNTS", std::to_string(b.counts)},
            {"PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM_OUT", std::to_string(b.frustum_out)},
            {"PENUMBRA_SAMPLE_LISTS_BINDING_OFFSETS", std::to_string(b.offsets)},
            {"PENUMBRA_SAMPLE_LISTS_BINDING_HEADER", std::to_string(b.header)},
            {"PENUMBRA_SAMPLE_LISTS_BINDING_LIST_POSITIONS", std::to_string(b.list_positions)},
            {"PENUMBRA_SAMPLE_LISTS_BINDING_LIST_IDS", std::to_string(b.list_ids)},
            {"PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_SLOTS", std::to_string(b.sample_slots)},
            {"PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_TEXELS", std::to_string(b.sample_texels)},
            {"PENUMBRA_SAMPLE_LISTS_UNIT_DEPTH", std::to_string(b.depth_unit)},
            {"PENUMBRA_SAMPLE_LISTS_UNIT_NORMALS", std::to_string(b.normal_unit)}};
        if (kernel == kCount || kernel == kScatter || kernel == kFit) {
            defines.push_back({"PENUMBRA_SAMPLE_LISTS_INPUT", std::to_string(input)});
        }
        defines.insert(defines.end(), extra.begin(), extra.end());
        return gl::buildComputeProgram(keys[kernel], defines, library);
    }

    void validateOutputs(const SampleListsSetup& setup, const SampleListsBuffers& out) const {
        const char* f = "SampleListBuilder::validate";
        const uint32_t a = ssbo_alignment_;
        gl::validateRange(out.counts, setup.counts_bytes, "counts", f, a);
        gl::validateRange(out.offsets, setup.offsets_bytes, "offsets", f, a);
        gl::validateRange(out.list_positions, setup.list_positions_bytes, "list_positions", f, a);
        gl::validateRange(out.list_ids, setup.list_ids_bytes, "list_ids", f, a);
        gl::validateRange(out.sample_slots, setup.sample_slots_bytes, "sample_slots", f, a);
        gl::validateRange(out.sample_texels, setup.sample_texels_bytes, "sample_texels", f, a);
        gl::validateRange(out.header, setup.header_bytes, "header", f, a);
        gl::validateRange(out.frustum, sizeof(SampleListsFrustum), "frustum", f,
                          std::max(ssbo_alignment_, ubo_alignment_));
    }

    Status checkAligned(const BufferRange& r, uint32_t alignment) const {
        return r.offset % alignment == 0 ? Status::Ok : Status::Misaligned;
    }

    Status checkBufferInput(const SampleListsSetup& setup, const SampleBufferInput& input,
                            const SampleListsOptions& options) const {
        const uint64_t bytes = uint64_t(setup.sample_count) * 16;
        if (!input.positions.holds(bytes) || (options.cull_back_facing && !input.normals.holds(bytes))) {
            return Status::RangeTooSmall;
        }
        if (checkAligned(input.positions, ssbo_alignment_) != Status::Ok ||
            (options.cull_back_facing && checkAligned(input.normals, ssbo_alignment_) != Status::Ok)) {
            return Status::Misaligned;
        }
        return Status::Ok;
    }

    Status checkOutputs(const SampleListsSetup& setup, const SampleListsBuffers& out, const SampleListsBuild&) const {
        if (setup.lists == 0 || setup.lists > reserved_lists_) return Status::NotReserved;
        const std::pair<const BufferRange*, uint64_t> ranges[] = {
            {&out.counts, setup.counts_bytes},       {&out.offsets, setup.offsets_bytes},
            {&out.list_positions, setup.list_positions_bytes}, {&out.list_ids, setup.list_ids_bytes},
            {&out.sample_slots, setup.sample_slots_bytes},     {&out.sample_texels, setup.sample_texels_bytes},
            {&out.header, setup.header_bytes},       {&out.frustum, sizeof(SampleListsFrustum)}};
        for (const auto& r : ranges) {
            if (!r.first->holds(r.second)) return Status::RangeTooSmall;
            if (r.second && checkAligned(*r.first, ssbo_alignment_) != Status::Ok) return Status::Misaligned;
        }
        if (checkAligned(out.frustum, ubo_alignment_) != Status::Ok) return Status::Misaligned;
        return Status::Ok;
    }

    void bindBufferInput(const SampleBufferInput& input, const SampleListsOptions& options) const {
        gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.positions, input.positions);
        if (options.cull_back_facing) gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.normals, input.normals);
    }

    void bindDepthInput(const SampleDepthInput& input, const SampleListsOptions& options) const {
        glBindTextureUnit(bindings_.depth_unit, input.depth_texture);
        glBindSampler(bindings_.depth_unit, sampler_);
        if (options.cull_back_facing) {
            glBindTextureUnit(bindings_.normal_unit, input.normal_texture);
            glBindSampler(bindings_.normal_unit, sampler_);
        }
    }

    void upload(const SampleListsParams& params) {
        glNamedBufferSubData(params_.id(), 0, sizeof params, &params);
        glBindBufferBase(GL_UNIFORM_BUFFER, bindings_.params, params_.id());
    }

    void runStatistics(const SampleListsSetup& setup, const SampleListsBuffers& lists) {
        detail::clearWords(lists.header, PENUMBRA_SAMPLE_LISTS_HEADER_STATISTICS_WORD, 4, 0u);
        programs_[kStatistics][0].use();
        gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.counts, lists.counts);
        gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.header, lists.header);
        detail::dispatch(setup.list_groups);
    }

    template <typename BindInput>
    void run(const SampleListsSetup& setup, const SampleListsParams& params, int input, BindInput&& bind_input,
             const SampleListsBuffers& out, const SampleListsBuild& build) {
        upload(params);
        // §3.1: "we initialize the local lists' lengths in the SM to zero".
        detail::clearWords(out.counts, 0, setup.lists, 0u);
        detail::clearWords(out.header, PENUMBRA_SAMPLE_LISTS_HEADER_COUNTERS_WORD,
                           PENUMBRA_SAMPLE_LISTS_HEADER_COUNTERS_WORDS, 0u);
        if (build.fit_frustum) {
            // §4.3 on the GPU: keys → header, then the crop → frustum (as an SSBO), read below as a UBO.
            detail::clearWords(out.header, PENUMBRA_SAMPLE_LISTS_HEADER_FIT_MIN_WORD, 2, 0xFFFFFFFFu);
            detail::clearWords(out.header, PENUMBRA_SAMPLE_LISTS_HEADER_FIT_MAX_WORD, 6, 0u);
            if (setup.sample_count) {
                programs_[kFit][input].use();
                bind_input();
                gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.header, out.header);
                detail::dispatch(setup.sample_groups);
            }
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            programs_[kFitResolve][0].use();
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.header, out.header);
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.frustum_out, out.frustum.sub(0, sizeof(SampleListsFrustum)));
            glDispatchCompute(1, 1, 1);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_UNIFORM_BARRIER_BIT);
        } else {
            const SampleListsFrustum f = sampleListsFrustum(params);
            glNamedBufferSubData(out.frustum.buffer, static_cast<GLintptr>(out.frustum.offset), sizeof f, &f);
        }
        gl::bindRange(GL_UNIFORM_BUFFER, bindings_.frustum, out.frustum.sub(0, sizeof(SampleListsFrustum)));
        // Pass 1: count.
        if (setup.sample_count) {
            programs_[kCount][input].use();
            bind_input();
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.counts, out.counts);
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.header, out.header);
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.sample_slots, out.sample_slots);
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.sample_texels, out.sample_texels);
            detail::dispatch(setup.sample_groups);
        }
        // Pass 2: offsets = exclusive scan of the lengths (§3.1, [HSO07]); the scanner issues the
        // barrier that makes pass 1's counts visible.
        const Status scanned = scanner_.exclusive(out.counts.sub(0, setup.counts_bytes),
                                                  out.offsets.sub(0, setup.offsets_bytes), setup.lists);
        PENUMBRA_ASSERT(scanned == Status::Ok);
        (void)scanned;
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        // Pass 3: scatter (the scanner left its own uniform/SSBO bindings: bind ours again).
        if (setup.sample_count) {
            programs_[kScatter][input].use();
            glBindBufferBase(GL_UNIFORM_BUFFER, bindings_.params, params_.id());
            bind_input();
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.offsets, out.offsets);
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.list_positions, out.list_positions);
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.list_ids, out.list_ids);
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.sample_slots, out.sample_slots);
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.sample_texels, out.sample_texels);
            detail::dispatch(setup.sample_groups);
        }
        if (build.statistics) {
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            runStatistics(setup, out);
        }
        glMemoryBarrier(kEndBarriers);
    }
};

/// Reads a GPU-built structure back into the CPU twin's form (waits for the GPU): for tests,
/// debugging and sampleListsDifference. Only the first `accepted` slots of the list arrays are read.
inline SampleListsCpu downloadSampleLists(const SampleListsSetup& setup, const SampleListsBuffers& lists) {
    SampleListsCpu out;
    out.grid_width = setup.grid_width;
    out.grid_height = setup.grid_height;
    out.header = SampleListBuilder::readHeader(lists.header);
    auto read = [](const BufferRange& range, size_t count, auto* data) {
        if (count) {
            glGetNamedBufferSubData(range.buffer, static_cast<GLintptr>(range.offset),
                                    GLsizeiptr(count * sizeof(*data)), data);
        }
    };
    PENUMBRA_CHECK(out.header.accepted <= setup.sample_count, "penumbra::downloadSampleLists: header says ",
                   out.header.accepted, " accepted samples of ", setup.sample_count);
    out.counts.resize(setup.lists);
    out.offsets.resize(setup.lists);
    out.list_positions.resize(out.header.accepted);
    out.list_ids.resize(out.header.accepted);
    out.sample_slots.resize(setup.sample_count);
    out.sample_texels.resize(setup.sample_count);
    read(lists.counts, out.counts.size(), out.counts.data());
    read(lists.offsets, out.offsets.size(), out.offsets.data());
    read(lists.list_positions, out.list_positions.size(), out.list_positions.data());
    read(lists.list_ids, out.list_ids.size(), out.list_ids.data());
    read(lists.sample_slots, out.sample_slots.size(), out.sample_slots.data());
    read(lists.sample_texels, out.sample_texels.size(), out.sample_texels.data());
    // Only the counters are part of the structure; fit and statistics words depend on other passes.
    SampleListsHeader counters{};
    counters.accepted = out.header.accepted;
    for (int r = 0; r < 8; ++r) counters.rejected[r] = out.header.rejected[r];
    out.header = counters;
    return out;
}

/// The list buffers a pipeline owns for its SampleListBuilder (every SampleListsBuffers range):
/// sized at load time by reserve(), handed to build() as ranges(). Shared by the hard and the
/// soft pipelines.
struct SampleListStorage {
    gl::Buffer counts, offsets, positions, ids, slots, texels, header, frustum;
    uint32_t samples = 0;  ///< view samples the per-sample buffers hold (0 before reserve)

    /// Load time: the per-texel buffers and the frustum block once, the per-sample ones for at
    /// least max(max_samples, 1) samples (empty buffers are not created; one element keeps the
    /// bindings valid). Returns true when the per-sample buffers were (re)allocated.
    bool reserve(const SampleListsSetup& setup, uint32_t max_samples) {
        if (!counts.id()) {
            counts = gl::Buffer(setup.counts_bytes);
            offsets = gl::Buffer(setup.offsets_bytes);
            header = gl::Buffer(setup.header_bytes);
        }
        if (!frustum.id()) frustum = gl::Buffer(sizeof(SampleListsFrustum));
        const uint32_t n = std::max<uint32_t>(max_samples, 1);
        if (samples != 0 && n <= samples) return false;
        positions = gl::Buffer(size_t(n) * 16);
        ids = gl::Buffer(size_t(n) * 4);
        slots = gl::Buffer(size_t(n) * 4);
        texels = gl::Buffer(size_t(n) * 4);
        samples = n;
        return true;
    }
    /// The whole buffers as the builder's ranges.
    SampleListsBuffers ranges() const {
        auto r = [](const gl::Buffer& b) { return BufferRange{b.id(), 0, b.size()}; };
        return {r(counts), r(offsets), r(positions), r(ids), r(slots), r(texels), r(header), r(frustum)};
    }
};

}  // namespace penumbra

#endif
