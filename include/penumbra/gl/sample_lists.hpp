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
//             It walks the steps planSampleLists (penumbra/sample_lists.hpp) returns as data —
//             one definition of the pass list, planned on the stack per build — binding every
//             resource of a dispatch right before it (SampleListsBindings: the plan's binding
//             points plus the scanner's); planOptions() gives planSampleLists this builder's
//             bindings, scan options and limits, for an engine that records the plan itself.
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

// The plan's barrier bits are GL's own.
static_assert(static_cast<GLbitfield>(SampleListsBarrier::Uniform) == GL_UNIFORM_BARRIER_BIT &&
                  static_cast<GLbitfield>(SampleListsBarrier::Command) == GL_COMMAND_BARRIER_BIT &&
                  static_cast<GLbitfield>(SampleListsBarrier::BufferUpdate) == GL_BUFFER_UPDATE_BARRIER_BIT &&
                  static_cast<GLbitfield>(SampleListsBarrier::Storage) == GL_SHADER_STORAGE_BARRIER_BIT,
              "SampleListsBarrier values must be the GL barrier bits");

/// Binding points of the builder's kernels (SampleListsBindingPoints: params, frustum, ...,
/// depth_unit, normal_unit; value-initialised = the sample_lists_shared.h defaults) and the
/// scanner's.
struct SampleListsBindings : SampleListsBindingPoints {
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

namespace detail {

inline void clearWords(const BufferRange& range, uint32_t first_word, uint32_t words, uint32_t value) {
    if (words == 0) return;
    glClearNamedBufferSubData(range.buffer, GL_R32UI, static_cast<GLintptr>(range.offset + uint64_t(first_word) * 4),
                              static_cast<GLsizeiptr>(uint64_t(words) * 4), GL_RED_INTEGER, GL_UNSIGNED_INT, &value);
}

inline void dispatch(const DispatchGrid& grid) {
    if (grid.groups) glDispatchCompute(grid.x, grid.y, 1);
}

inline GLbitfield glBarrierBits(SampleListsBarrier barriers) { return static_cast<GLbitfield>(barriers); }

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
        for (uint32_t kernel = 0; kernel < kSampleListsKernels; ++kernel) {
            const auto k = static_cast<SampleListsKernel>(kernel);
            for (uint32_t input = 0; input < (sampleListsKernelPerInput(k) ? 2u : 1u); ++input) {
                programs_[kernel][input] =
                    buildKernel(k, static_cast<SampleListsInputKind>(input), library, extra_defines);
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
            for (uint32_t k = 0; k < kSampleListsKernels; ++k) {
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
        run(setup, detail::makeSampleListsParams(setup, light, options, nullptr, build.fit),
            SampleListsInputKind::Buffer, &input, nullptr, out, options, build);
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
        run(setup, detail::makeSampleListsParams(setup, light, options, &input.view, build.fit),
            SampleListsInputKind::Depth, nullptr, &input, out, options, build);
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
    /// The options planSampleLists needs to describe this builder's builds (its binding points,
    /// its scanner's options and the driver's limits) for ranges at the given byte offsets.
    SampleListsPlanOptions planOptions(uint64_t counts_offset = 0, uint64_t offsets_offset = 0) const {
        SampleListsPlanOptions o;
        o.bindings = bindings_;
        o.scan = scanner_.options();
        o.scan_limits = scanner_.limits();
        o.counts_offset = counts_offset;
        o.offsets_offset = offsets_offset;
        return o;
    }
    const Scanner& scanner() const { return scanner_; }
    /// GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT: every SSBO range offset must be a multiple.
    uint32_t storageAlignment() const { return ssbo_alignment_; }

private:
    static constexpr GLbitfield kEndBarriers = static_cast<GLbitfield>(kSampleListsEndBarriers);

    SampleListsBindings bindings_;
    Scanner scanner_;
    gl::Program programs_[kSampleListsKernels][2];  ///< [kernel][input kind]; per-input kernels only use both
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

    gl::Program buildKernel(SampleListsKernel kernel, SampleListsInputKind input, const ShaderLibrary& library,
                            const ShaderDefines& extra) const {
        ShaderDefines defines = sampleListsKernelDefines(kernel, input, bindings_);
        defines.insert(defines.end(), extra.begin(), extra.end());
        return gl::buildComputeProgram(sampleListsKernelKey(kernel), defines, library);
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

    void upload(const SampleListsParams& params) {
        glNamedBufferSubData(params_.id(), 0, sizeof params, &params);
        gl::bindBase(GL_UNIFORM_BUFFER, bindings_.params, params_.id());
    }

    void runStatistics(const SampleListsSetup& setup, const SampleListsBuffers& lists) {
        detail::clearWords(lists.header, PENUMBRA_SAMPLE_LISTS_HEADER_STATISTICS_WORD, 4, 0u);
        programs_[static_cast<uint32_t>(SampleListsKernel::Statistics)][0].use();
        gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.counts, lists.counts);
        gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.header, lists.header);
        detail::dispatch(setup.list_groups);
    }

    /// The range a plan resource names (Params: the builder's own uniform buffer).
    BufferRange rangeOf(SampleListsResource r, const SampleBufferInput* in, const SampleListsBuffers& out) const {
        using R = SampleListsResource;
        switch (r) {
            case R::Params: return {params_.id(), 0, sizeof(SampleListsParams)};
            case R::Frustum: return out.frustum;
            case R::Positions: return in ? in->positions : BufferRange{};
            case R::Normals: return in ? in->normals : BufferRange{};
            case R::Counts: return out.counts;
            case R::Offsets: return out.offsets;
            case R::ListPositions: return out.list_positions;
            case R::ListIds: return out.list_ids;
            case R::SampleSlots: return out.sample_slots;
            case R::SampleTexels: return out.sample_texels;
            case R::Header: return out.header;
            default: return {};
        }
    }

    // One build: walks the plan's steps (detail::planSampleListsSteps, the same list
    // planSampleLists returns), planned on the stack — no allocation, no query, no exception.
    void run(const SampleListsSetup& setup, const SampleListsParams& params, SampleListsInputKind input,
             const SampleBufferInput* buffer_input, const SampleDepthInput* depth_input, const SampleListsBuffers& out,
             const SampleListsOptions& options, const SampleListsBuild& build) {
        SampleListsSteps steps;
        detail::planSampleListsSteps(setup, build, input, options.cull_back_facing, bindings_, steps);
        for (const SampleListsStep& step : steps) {
            switch (step.kind) {
                case SampleListsStepKind::Upload:
                    if (step.resource == SampleListsResource::Params) {
                        glNamedBufferSubData(params_.id(), 0, sizeof params, &params);
                    } else {
                        const SampleListsFrustum f = sampleListsFrustum(params);
                        glNamedBufferSubData(out.frustum.buffer, static_cast<GLintptr>(out.frustum.offset), sizeof f,
                                             &f);
                    }
                    break;
                case SampleListsStepKind::Clear:
                    detail::clearWords(rangeOf(step.resource, buffer_input, out), step.first_word, step.words,
                                       step.value);
                    break;
                case SampleListsStepKind::Dispatch: {
                    const uint32_t kernel = static_cast<uint32_t>(step.kernel);
                    programs_[kernel][sampleListsKernelPerInput(step.kernel) ? static_cast<uint32_t>(input) : 0u].use();
                    for (uint32_t i = 0; i < step.binding_count; ++i) {
                        const SampleListsBinding& b = step.bindings[i];
                        if (b.kind == SampleListsBindingKind::Texture) {
                            const GLuint texture = b.resource == SampleListsResource::DepthTexture
                                                       ? depth_input->depth_texture
                                                       : depth_input->normal_texture;
                            glBindTextureUnit(b.point, texture);
                            glBindSampler(b.point, sampler_);
                            continue;
                        }
                        const GLenum target = b.kind == SampleListsBindingKind::UniformBuffer ? GL_UNIFORM_BUFFER
                                                                                             : GL_SHADER_STORAGE_BUFFER;
                        gl::bindRange(target, b.point, rangeOf(b.resource, buffer_input, out).sub(0, b.bytes));
                    }
                    glDispatchCompute(step.grid.x, step.grid.y, 1);
                    break;
                }
                case SampleListsStepKind::Scan: {
                    const uint64_t bytes = uint64_t(step.elements) * 4;
                    const Status scanned =
                        scanner_.exclusive(rangeOf(step.resource, buffer_input, out).sub(0, bytes),
                                           rangeOf(step.output, buffer_input, out).sub(0, bytes), step.elements);
                    PENUMBRA_ASSERT(scanned == Status::Ok);
                    (void)scanned;
                    break;
                }
                case SampleListsStepKind::Barrier: glMemoryBarrier(detail::glBarrierBits(step.barriers)); break;
            }
        }
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
