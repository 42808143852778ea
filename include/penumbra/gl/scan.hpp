// penumbra — the GL executor of the buffer scan: penumbra::Scanner (GL 4.5, compute shaders).
//
// Integration summary
//   needs:    PENUMBRA_GL_HEADER (see gl.hpp) and a current GL 4.5 context; shaders from the
//             embedded table (or a ShaderLibrary you pass). Includes penumbra/scan.hpp (the GL-free
//             setup, plan and CPU twin).
//   setup:    Scanner(options, library, bindings) compiles the kernels (and, where a subgroup path
//             is picked, runs a small check scan with read-back); reserve(max_n) sizes the scratch
//             and constants buffers and the plan storage for every n <= max_n; validate(in, out,
//             n) checks your ranges against GL_BUFFER_SIZE once (queries, throws penumbra::Error).
//   per frame: scan / exclusive / inclusive(input range, output range, n): records the plan's
//             dispatches (one glNamedBufferSubData of all their constants, then per dispatch
//             glBindBuffersRange + glUseProgram + glMemoryBarrier + glDispatchCompute). No heap
//             allocation, no glGet* / glIs* / glGetError, no read-back, no exception. Misuse it
//             can see without GL returns a Status after PENUMBRA_ASSERT and issues no GL call:
//               NotReserved      n > the largest reserve() (also a moved-from Scanner);
//               Misaligned       a range offset that is not a multiple of 4;
//               RangeTooSmall    a range with buffer 0 or shorter than n * 4 bytes;
//               InvalidArgument  input and output ranges in one buffer that overlap without
//                                starting at the same offset (in place = identical offsets).
//             The ranges' sizes are your word (validate() checks them against GL once).
//
// GL state contract of scan / exclusive / inclusive (n > 0 and Status::Ok):
//   * the first dispatch is preceded by glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT), so shader
//     writes you made to the input in earlier dispatches/draws (SSBO, image or atomic-counter
//     stores) are visible; writes through glBufferSubData / copies / clears need nothing;
//   * the scanner's compute dispatches are separated by the same barrier, and none follows the
//     last one: before you read the output issue the barrier for how you read it —
//     GL_SHADER_STORAGE_BARRIER_BIT for SSBO reads in shaders, GL_BUFFER_UPDATE_BARRIER_BIT for
//     glGetBufferSubData / mapping, GL_COMMAND_BARRIER_BIT for indirect draws/dispatches,
//     GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT / GL_ELEMENT_ARRAY_BARRIER_BIT for vertex or index pulls,
//     GL_UNIFORM_BARRIER_BIT for UBO reads;
//   * it changes and does not restore (nothing is reset or unbound): the current program (left
//     at one of the scanner's programs); the indexed GL_SHADER_STORAGE_BUFFER bindings
//     ScanBindings::input, output, partials, input_vec4, output_vec4 (those the plan's dispatches
//     bind; they are left pointing at your ranges or the scanner's scratch) and the indexed
//     GL_UNIFORM_BUFFER binding ScanBindings::constants (left at the scanner's constants buffer).
//     Bindings go through glBindBuffersRange, which leaves the generic GL_SHADER_STORAGE_BUFFER /
//     GL_UNIFORM_BUFFER bindings alone. Nothing else: no VAO, framebuffer, texture, image or
//     sampler state, no other binding index, no glGetError (your queued GL errors stay queued);
//     penumbra/gl/state.hpp's StateSave restores everything if you want that;
//   * n == 0, or any Status other than Ok: no GL call at all.
//   The constants are rewritten by every scan (one glNamedBufferSubData into the scanner's own
//   uniform buffer), so several scans per frame with one Scanner are fine.
//
// Errors at setup (penumbra::Error naming the value): bad ScanOptions (group size not a power of
// two in [32, driver maximum], items per thread not a multiple of 4 in [4, 64], window_elements
// below one group's worth), ScanBindings out of the driver's range or SSBO bindings that coincide,
// reserve(n) with n > kScanMaxElements or a failed allocation, validate() with a name that is not
// a buffer, a buffer without storage, a range past GL_BUFFER_SIZE, or overlapping ranges.
// Setup never drains the GL error queue: reserve() detects a failed allocation by querying
// GL_BUFFER_SIZE of the new buffer (0 when glNamedBufferStorage failed), so errors your code
// queued before stay queued — and the GL_OUT_OF_MEMORY of a failed allocation stays in the queue
// too.
#ifndef PENUMBRA_GL_SCAN_HPP
#define PENUMBRA_GL_SCAN_HPP

#include "penumbra/buffer_range.hpp"
#include "penumbra/gl/gl.hpp"
#include "penumbra/gl/shader.hpp"
#include "penumbra/gl/validate.hpp"
#include "penumbra/scan.hpp"

#include <array>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

// GL_KHR_shader_subgroup enums, for loaders generated without the extension.
#ifndef GL_SUBGROUP_SIZE_KHR
#define GL_SUBGROUP_SIZE_KHR 0x9532
#endif
#ifndef GL_SUBGROUP_SUPPORTED_STAGES_KHR
#define GL_SUBGROUP_SUPPORTED_STAGES_KHR 0x9533
#endif
#ifndef GL_SUBGROUP_SUPPORTED_FEATURES_KHR
#define GL_SUBGROUP_SUPPORTED_FEATURES_KHR 0x9534
#endif
#ifndef GL_SUBGROUP_FEATURE_BASIC_BIT_KHR
#define GL_SUBGROUP_FEATURE_BASIC_BIT_KHR 0x00000001
#endif
#ifndef GL_SUBGROUP_FEATURE_ARITHMETIC_BIT_KHR
#define GL_SUBGROUP_FEATURE_ARITHMETIC_BIT_KHR 0x00000004
#endif

namespace penumbra {

namespace detail {

inline bool glHasExtension(const char* name) {
    const GLint count = gl::getInteger(GL_NUM_EXTENSIONS);
    for (GLint i = 0; i < count; ++i) {
        const char* ext = reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, static_cast<GLuint>(i)));
        if (ext && std::strcmp(ext, name) == 0) return true;
    }
    return false;
}

/// Subgroup size when compute shaders have GL_KHR_shader_subgroup basic + arithmetic, else 0.
inline uint32_t computeSubgroupSize() {
    if (!glHasExtension("GL_KHR_shader_subgroup")) return 0;
    const GLint stages = gl::getInteger(GL_SUBGROUP_SUPPORTED_STAGES_KHR);
    const GLint features = gl::getInteger(GL_SUBGROUP_SUPPORTED_FEATURES_KHR);
    const GLint size = gl::getInteger(GL_SUBGROUP_SIZE_KHR);
    const GLint needed = GL_SUBGROUP_FEATURE_BASIC_BIT_KHR | GL_SUBGROUP_FEATURE_ARITHMETIC_BIT_KHR;
    if (!(stages & GL_COMPUTE_SHADER_BIT) || (features & needed) != needed || size <= 0) return 0;
    return static_cast<uint32_t>(size);
}

/// An owned immutable-storage buffer (glNamedBufferStorage) whose allocation is checked with a
/// GL_BUFFER_SIZE query, never glGetError (see the file comment).
class ScanOwnedBuffer {
public:
    ScanOwnedBuffer() = default;
    ScanOwnedBuffer(ScanOwnedBuffer&& other) noexcept
        : id_(std::exchange(other.id_, 0)), bytes_(std::exchange(other.bytes_, 0)) {}
    ScanOwnedBuffer& operator=(ScanOwnedBuffer&& other) noexcept {
        if (this != &other) {
            reset();
            id_ = std::exchange(other.id_, 0);
            bytes_ = std::exchange(other.bytes_, 0);
        }
        return *this;
    }
    ScanOwnedBuffer(const ScanOwnedBuffer&) = delete;
    ScanOwnedBuffer& operator=(const ScanOwnedBuffer&) = delete;
    ~ScanOwnedBuffer() { reset(); }

    GLuint id() const { return id_; }
    uint64_t bytes() const { return bytes_; }
    /// Grows to at least `bytes` (contents are not kept). Throws penumbra::Error naming `what`.
    void grow(uint64_t bytes, GLbitfield flags, const char* what) {
        if (bytes <= bytes_) return;
        reset();
        GLuint id = 0;
        glCreateBuffers(1, &id);
        PENUMBRA_CHECK(id != 0, "penumbra::Scanner::reserve: glCreateBuffers failed for the ", what, " buffer");
        glNamedBufferStorage(id, static_cast<GLsizeiptr>(bytes), nullptr, flags);
        GLint64 size = 0;
        glGetNamedBufferParameteri64v(id, GL_BUFFER_SIZE, &size);
        if (static_cast<uint64_t>(size) != bytes) {
            glDeleteBuffers(1, &id);
            ::penumbra::detail::fail("penumbra::Scanner::reserve: allocating ", bytes, " bytes of scan ", what,
                                     " failed (GL_BUFFER_SIZE ", size, " afterwards; GL's own error stays queued)");
        }
        id_ = id;
        bytes_ = bytes;
    }
    void reset() {
        if (id_) gl::deleteBuffers(1, &id_);  // bound at indexed points: keeps the generic ones
        id_ = 0;
        bytes_ = 0;
    }

private:
    GLuint id_ = 0;
    uint64_t bytes_ = 0;
};

}  // namespace detail

/// The current context's limits for planScan (needs a current GL context).
inline ScanLimits queryScanLimits() {
    ScanLimits limits;
    GLint64 block = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &block);
    limits.max_binding_bytes = static_cast<uint64_t>(block);
    limits.binding_alignment = static_cast<uint32_t>(gl::getInteger(GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT));
    limits.max_groups_x = static_cast<uint64_t>(gl::getInteger(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 0));
    limits.max_groups_y = static_cast<uint64_t>(gl::getInteger(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 1));
    limits.max_group_size = static_cast<uint32_t>(std::min(gl::getInteger(GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS),
                                                           gl::getInteger(GL_MAX_COMPUTE_WORK_GROUP_SIZE, 0)));
    limits.uniform_alignment = static_cast<uint32_t>(gl::getInteger(GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT));
    PENUMBRA_CHECK(limits.max_binding_bytes > 0 && limits.binding_alignment > 0 && limits.max_groups_x > 0 &&
                       limits.max_groups_y > 0 && limits.uniform_alignment > 0,
                   "penumbra: the driver reported unusable compute limits (is a GL 4.5 context current?)");
    return limits;
}

/// Where the scan kernels find their buffers. Defaults: the PENUMBRA_SCAN_BINDING_* of
/// scan_shared.h. The five shader-storage indices must differ; constants is a uniform-buffer index.
struct ScanBindings {
    uint32_t input = PENUMBRA_SCAN_BINDING_INPUT;
    uint32_t output = PENUMBRA_SCAN_BINDING_OUTPUT;
    uint32_t partials = PENUMBRA_SCAN_BINDING_PARTIALS;
    uint32_t input_vec4 = PENUMBRA_SCAN_BINDING_INPUT_VEC4;
    uint32_t output_vec4 = PENUMBRA_SCAN_BINDING_OUTPUT_VEC4;
    uint32_t constants = PENUMBRA_SCAN_BINDING_CONSTANTS;  ///< GL_UNIFORM_BUFFER binding
};

/// Scans uint buffer ranges on the GPU (see the summary at the top of this file and of
/// penumbra/scan.hpp). Owns its programs, a scratch buffer and a constants buffer: RAII, movable,
/// not copyable; create, use and destroy it with the same GL context current. A moved-from
/// Scanner may be destroyed, assigned to, or called (scan() then returns Status::NotReserved).
class Scanner {
public:
    /// Needs a current GL 4.5 context; queries the limits and compiles six programs (reduce, scan
    /// and top passes; uvec4 and scalar addressing), pointing their blocks at `bindings`. Throws
    /// penumbra::Error for bad options or bindings and shader errors. Picking a subgroup path
    /// runs a small check scan (its own buffers, read back; the state changes of a scan).
    explicit Scanner(const ScanOptions& options = {}, const ShaderLibrary& library = ShaderLibrary::embedded(),
                     const ScanBindings& bindings = {})
        : limits_(queryScanLimits()), bindings_(bindings) {
        options_ = detail::validateScanSetup(options, limits_);
        checkBindings();
        for (int vec4 = 0; vec4 < 2; ++vec4) {
            buildKernel(kReduce, vec4, "penumbra/scan/scan.comp.glsl", library);
            buildKernel(kScan, vec4, "penumbra/scan/scan.comp.glsl", library);
        }
        // Top-pass workgroup scan: KHR subgroup arithmetic where the driver has it, else ARB
        // ballot, else shared memory. A subgroup mode is kept only if a small scan matches the CPU
        // twin: it assumes subgroups of consecutive invocations, which GL does not promise (and
        // ballot's subgroup size cannot even be queried).
        if (options_.allow_subgroups) {
            const uint32_t khr = detail::computeSubgroupSize();
            if (khr != 0 && options_.group_size % khr == 0) {
                subgroups_ = ScanSubgroups::Khr;
            } else if (detail::glHasExtension("GL_ARB_shader_ballot")) {
                subgroups_ = ScanSubgroups::Ballot;
            }
        }
        buildTopKernels(library);
        if (subgroups_ != ScanSubgroups::None && !selfCheck()) {
            subgroups_ = ScanSubgroups::None;
            buildTopKernels(library);
        }
    }

    Scanner(Scanner&& other) noexcept { *this = std::move(other); }
    Scanner& operator=(Scanner&& other) noexcept {
        if (this != &other) {
            options_ = other.options_;
            limits_ = other.limits_;
            bindings_ = other.bindings_;
            subgroups_ = other.subgroups_;
            for (int p = 0; p < kPasses; ++p) {
                for (int v = 0; v < 2; ++v) kernels_[p][v] = std::move(other.kernels_[p][v]);
            }
            scratch_ = std::move(other.scratch_);
            constants_ = std::move(other.constants_);
            frame_ = std::move(other.frame_);
            staging_ = std::move(other.staging_);
            reserved_ = std::exchange(other.reserved_, 0);
            dispatch_capacity_ = std::exchange(other.dispatch_capacity_, 0);
        }
        return *this;
    }
    Scanner(const Scanner&) = delete;
    Scanner& operator=(const Scanner&) = delete;
    ~Scanner() = default;

    /// Setup: makes every n <= max_n scannable — grows the scratch and constants buffers and the
    /// plan storage to the bounds over all such n. Capacity only grows. Throws penumbra::Error for
    /// max_n > kScanMaxElements, limits that cannot run it, or a failed allocation (detected by a
    /// GL_BUFFER_SIZE query; the GL error queue is not touched).
    void reserve(uint64_t max_n) {
        planScan(max_n, options_, limits_);  // checks n, grids and scratch against the limits
        const detail::ScanBounds bounds = detail::scanBounds(max_n, options_, limits_);
        const uint32_t stride = detail::scanConstantsStride(limits_);
        scratch_.grow(std::max<uint64_t>(bounds.scratch_bytes, 16), 0, "scratch");
        constants_.grow(std::max<uint64_t>(bounds.dispatches, 1) * stride, GL_DYNAMIC_STORAGE_BIT, "constants");
        if (bounds.dispatches > dispatch_capacity_) {
            frame_.dispatch_list.reserve(static_cast<size_t>(bounds.dispatches));
            frame_.constants.reserve(static_cast<size_t>(bounds.dispatches));
            staging_.resize(static_cast<size_t>(bounds.dispatches * stride));
            dispatch_capacity_ = bounds.dispatches;
        }
        reserved_ = std::max(reserved_, max_n);
    }

    /// Load-time check of the ranges a later scan(…, n) will use (GL queries; throws
    /// penumbra::Error naming the problem): n reserved, both ranges name buffers with storage,
    /// lie inside GL_BUFFER_SIZE, have offsets that are multiples of 4 and hold n * 4 bytes, and
    /// do not overlap unless identical.
    void validate(const BufferRange& input, const BufferRange& output, uint64_t n) const {
        PENUMBRA_CHECK(n <= reserved_, "penumbra::Scanner::validate: n = ", n, " exceeds the reserved ", reserved_,
                       " (call reserve(", n, ") at load time)");
        gl::validateRange(input, n * 4, "input", "Scanner::validate");
        gl::validateRange(output, n * 4, "output", "Scanner::validate");
        PENUMBRA_CHECK(!overlaps(input, output, n), "penumbra::Scanner::validate: input offset ", input.offset,
                       " and output offset ", output.offset, " of n = ", n, " elements in buffer ", input.buffer,
                       " overlap without being equal (in place needs equal offsets)");
    }

    /// Per frame: scans n uints of `input` into `output` (the same range: in place). See the
    /// Status list and the GL state contract at the top of this file.
    Status scan(ScanKind kind, const BufferRange& input, const BufferRange& output, uint64_t n) {
        if (n == 0) return Status::Ok;
        if (n > reserved_) {
            PENUMBRA_ASSERT(n <= reserved_ && "penumbra::Scanner::scan: n exceeds reserve()");
            return Status::NotReserved;
        }
        if (input.offset % 4 != 0 || output.offset % 4 != 0) {
            PENUMBRA_ASSERT(input.offset % 4 == 0 && output.offset % 4 == 0 &&
                            "penumbra::Scanner::scan: range offsets must be multiples of 4");
            return Status::Misaligned;
        }
        if (!input.holds(n * 4) || !output.holds(n * 4)) {
            PENUMBRA_ASSERT(input.holds(n * 4) && output.holds(n * 4) &&
                            "penumbra::Scanner::scan: a range is null or shorter than n * 4 bytes");
            return Status::RangeTooSmall;
        }
        if (overlaps(input, output, n)) {
            PENUMBRA_ASSERT(!overlaps(input, output, n) &&
                            "penumbra::Scanner::scan: input and output overlap without being identical");
            return Status::InvalidArgument;
        }
        // Plan into the storage reserve() sized: no allocation (capacity >= every n <= reserved;
        // the check below only guards that bound).
        detail::planScanShape(n, kind, input.offset, output.offset, options_, limits_, frame_);
        if (frame_.dispatches > dispatch_capacity_) {
            PENUMBRA_ASSERT(frame_.dispatches <= dispatch_capacity_ && "penumbra::Scanner::scan: reserve() bound");
            return Status::NotReserved;
        }
        frame_.dispatch_list.clear();
        frame_.constants.clear();
        const uint32_t stride = detail::scanConstantsStride(limits_);
        unsigned char* staging = staging_.data();
        detail::forEachScanDispatch(frame_, [&](const ScanDispatch& d, const shared::PenumbraScanConstants& c) {
            std::memcpy(staging + d.constants.offset, &c, sizeof c);
            frame_.dispatch_list.push_back(d);
        });
        const size_t count = frame_.dispatch_list.size();
        glNamedBufferSubData(constants_.id(), 0,
                             static_cast<GLsizeiptr>((count - 1) * stride + sizeof(shared::PenumbraScanConstants)),
                             staging);
        GLuint current = 0;
        for (const ScanDispatch& d : frame_.dispatch_list) {
            const GLuint program = kernels_[static_cast<int>(d.pass)][d.vec4 ? 1 : 0].id();
            bind(GL_SHADER_STORAGE_BUFFER, bindings_.input, d.input, input.buffer, output.buffer);
            if (d.vec4) bind(GL_SHADER_STORAGE_BUFFER, bindings_.input_vec4, d.input, input.buffer, output.buffer);
            bind(GL_SHADER_STORAGE_BUFFER, bindings_.output, d.output, input.buffer, output.buffer);
            if (d.vec4) bind(GL_SHADER_STORAGE_BUFFER, bindings_.output_vec4, d.output, input.buffer, output.buffer);
            bind(GL_SHADER_STORAGE_BUFFER, bindings_.partials, d.partials, input.buffer, output.buffer);
            bind(GL_UNIFORM_BUFFER, bindings_.constants, d.constants, input.buffer, output.buffer);
            if (program != current) glUseProgram(program);
            current = program;
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            glDispatchCompute(d.grid.x, d.grid.y, 1);
        }
        return Status::Ok;
    }
    Status exclusive(const BufferRange& input, const BufferRange& output, uint64_t n) {
        return scan(ScanKind::Exclusive, input, output, n);
    }
    Status inclusive(const BufferRange& input, const BufferRange& output, uint64_t n) {
        return scan(ScanKind::Inclusive, input, output, n);
    }

    /// The plan scan(n) executes for an exclusive scan of ranges at offset 0 (pure arithmetic;
    /// allocates the dispatch list: not for frames).
    ScanPlan plan(uint64_t n) const { return planScan(n, options_, limits_); }
    /// The plan of scan(kind, input, output, n): the shifts follow the ranges' offsets.
    ScanPlan plan(ScanKind kind, const BufferRange& input, const BufferRange& output, uint64_t n) const {
        return planScan(n, options_, limits_, kind, input.offset, output.offset);
    }
    /// Scratch bytes a scan of n elements needs (0 when one group covers n). Pure arithmetic.
    size_t scratchBytes(uint64_t n) const { return static_cast<size_t>(plan(n).scratch_bytes); }
    /// The largest n reserve() prepared (0: none; scan() returns NotReserved for any n > 0).
    uint64_t reserved() const { return reserved_; }

    /// True when the top pass's workgroup scan uses subgroup operations (see subgroupMode()).
    bool usesSubgroups() const { return subgroups_ != ScanSubgroups::None; }
    /// Khr: GL_KHR_shader_subgroup arithmetic in compute shaders and a group size that is a
    /// multiple of GL_SUBGROUP_SIZE_KHR; else Ballot: GL_ARB_shader_ballot; either kept only if a
    /// small scan at construction matched the CPU twin; else None (shared memory only). Always
    /// None with ScanOptions::allow_subgroups = false. The bulk passes use no cross-invocation
    /// operations in any mode.
    ScanSubgroups subgroupMode() const { return subgroups_; }
    const ScanOptions& options() const { return options_; }  ///< resolved (no zeros)
    const ScanLimits& limits() const { return limits_; }
    const ScanBindings& bindings() const { return bindings_; }
    GLuint scratchBuffer() const { return scratch_.id(); }
    size_t scratchCapacity() const { return static_cast<size_t>(scratch_.bytes()); }
    GLuint constantsBuffer() const { return constants_.id(); }
    size_t constantsCapacity() const { return static_cast<size_t>(constants_.bytes()); }
    /// The program of a pass and addressing (for inspection and tests; owned by the Scanner).
    GLuint program(ScanPass pass, bool vec4) const { return kernels_[static_cast<int>(pass)][vec4 ? 1 : 0].id(); }

private:
    static constexpr int kReduce = static_cast<int>(ScanPass::Reduce), kScan = static_cast<int>(ScanPass::Scan),
                         kTop = static_cast<int>(ScanPass::Top), kPasses = 3;

    ScanOptions options_;
    ScanLimits limits_;
    ScanBindings bindings_;
    ScanSubgroups subgroups_ = ScanSubgroups::None;
    gl::Program kernels_[kPasses][2];  ///< [pass][addressing: scalar, uvec4]
    detail::ScanOwnedBuffer scratch_;
    detail::ScanOwnedBuffer constants_;
    ScanPlan frame_;                      ///< per-frame plan storage (capacity from reserve())
    std::vector<unsigned char> staging_;  ///< every dispatch's constants, at their UBO offsets
    uint64_t reserved_ = 0;
    uint64_t dispatch_capacity_ = 0;

    static bool overlaps(const BufferRange& a, const BufferRange& b, uint64_t n) {
        if (a.buffer != b.buffer || a.offset == b.offset) return false;
        const uint64_t bytes = n * 4;
        return !(a.offset + bytes <= b.offset || b.offset + bytes <= a.offset);
    }

    // One indexed binding through glBindBuffersRange (leaves the generic binding alone).
    void bind(GLenum target, GLuint index, const ScanBinding& b, GLuint input, GLuint output) const {
        GLuint buffer = 0;
        switch (b.buffer) {
            case ScanBuffer::None: return;
            case ScanBuffer::Input: buffer = input; break;
            case ScanBuffer::Output: buffer = output; break;
            case ScanBuffer::Scratch: buffer = scratch_.id(); break;
            case ScanBuffer::Constants: buffer = constants_.id(); break;
        }
        const GLintptr offset = static_cast<GLintptr>(b.offset);
        const GLsizeiptr size = static_cast<GLsizeiptr>(b.size);
        glBindBuffersRange(target, index, 1, &buffer, &offset, &size);
    }

    std::array<gl::BlockBinding, 5> storageBlocks() const {
        return {{{"input", "PenumbraScanInput", bindings_.input},
                 {"output", "PenumbraScanOutput", bindings_.output},
                 {"partials", "PenumbraScanPartials", bindings_.partials},
                 {"input_vec4", "PenumbraScanInputQuads", bindings_.input_vec4},
                 {"output_vec4", "PenumbraScanOutputQuads", bindings_.output_vec4}}};
    }

    void checkBindings() const {
        const auto storage = storageBlocks();
        gl::checkBlockBindings("ScanBindings", storage.data(), int(storage.size()), "constants", bindings_.constants);
    }

    // Re-points a program's blocks at bindings_ (program state, set once at construction).
    void pointBlocks(GLuint program) const {
        const auto storage = storageBlocks();
        gl::pointBlocks(program, storage.data(), int(storage.size()), "PenumbraScanConstantsBlock", bindings_.constants);
    }

    void buildKernel(int pass, int vec4, const char* key, const ShaderLibrary& library) {
        static const char* const kPassNames[kPasses] = {"PENUMBRA_SCAN_PASS_REDUCE", "PENUMBRA_SCAN_PASS_SCAN",
                                                        "PENUMBRA_SCAN_PASS_TOP"};
        const ShaderDefines defines = {{"PENUMBRA_SCAN_PASS", kPassNames[pass]},
                                       {"PENUMBRA_SCAN_GROUP_SIZE", std::to_string(options_.group_size)},
                                       {"PENUMBRA_SCAN_ITEMS_PER_THREAD", std::to_string(options_.items_per_thread)},
                                       {"PENUMBRA_SCAN_VEC4", vec4 ? "1" : "0"}};
        kernels_[pass][vec4] = gl::buildComputeProgram(key, defines, library);
        pointBlocks(kernels_[pass][vec4].id());
    }

    void buildTopKernels(const ShaderLibrary& library) {
        const char* key = subgroups_ == ScanSubgroups::Khr      ? "penumbra/scan/scan_subgroups.comp.glsl"
                          : subgroups_ == ScanSubgroups::Ballot ? "penumbra/scan/scan_ballot.comp.glsl"
                                                                : "penumbra/scan/scan.comp.glsl";
        for (int vec4 = 0; vec4 < 2; ++vec4) buildKernel(kTop, vec4, key, library);
    }

    // Setup only (reads back): scans one group's worth + 2 * items + 7 elements of a fixed pattern
    // (reduce, top, scan, the tail window's carry) into an aligned and a misaligned range (uvec4
    // and scalar kernels) and compares with scanCpu. Leaves reserved() at 0 (the buffers stay).
    bool selfCheck() {
        const uint64_t n = (uint64_t(options_.group_size) + 2) * options_.items_per_thread + 7;
        std::vector<uint32_t> values(n), want(n), got(n);
        for (uint64_t i = 0; i < n; ++i) values[i] = static_cast<uint32_t>(i * 2654435761u + 12345u);
        scanCpu(values.data(), want.data(), n, ScanKind::Exclusive);
        GLuint buffers[2] = {0, 0};
        glCreateBuffers(2, buffers);
        glNamedBufferStorage(buffers[0], static_cast<GLsizeiptr>(n * 4), values.data(), 0);
        glNamedBufferStorage(buffers[1], static_cast<GLsizeiptr>(n * 4 + 4), nullptr, 0);
        reserve(n);
        bool ok = true;
        for (uint64_t offset : {uint64_t(0), uint64_t(4)}) {
            ok = ok && scan(ScanKind::Exclusive, {buffers[0], 0, n * 4}, {buffers[1], offset, n * 4}, n) == Status::Ok;
            glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
            glGetNamedBufferSubData(buffers[1], static_cast<GLintptr>(offset), static_cast<GLsizeiptr>(n * 4),
                                    got.data());
            ok = ok && got == want;
        }
        gl::deleteBuffers(2, buffers);  // bound at ScanBindings' points: keeps the generic ones
        reserved_ = 0;
        return ok;
    }
};

}  // namespace penumbra

#endif
