// penumbra — prefix sums (scan) of uint buffers on the GPU, and their CPU twin.
//
// sintorn2008 §3.1 turns per-texel list counts into list offsets with a scan [Harris, Sengupta,
// Owens 2007, "Parallel Prefix Sum (Scan) with CUDA", GPU Gems 3 ch. 39]. This block is that scan
// for any uint buffer: out[i] = in[0] + ... + in[i-1] (exclusive) or + in[i] (inclusive), mod 2^32,
// exactly what std::exclusive_scan / std::inclusive_scan give on uint32_t.
//
// Integration summary
//   needs:    PENUMBRA_GL_HEADER (see gl/gl.hpp) and, for Scanner, a current GL 4.5 context;
//             shaders from the embedded table (or a ShaderLibrary you pass).
//   produces: Scanner::exclusive / inclusive / scan: n uints of one buffer range scanned into
//             another range (or the same range: in place), n from 0 to kScanMaxElements, byte
//             offsets that are multiples of 4. scanCpu: the CPU twin (also a fallback).
//   pure setup (no GL, unit-tested): planScan() — windows, levels, tiles, dispatch grids, scratch
//             bytes, dispatch count. Define PENUMBRA_SCAN_NO_GL to get only this and scanCpu.
//   GPU code: shaders/penumbra/scan/scan.comp.glsl (reduce, scan and top passes),
//             scan_subgroups.comp.glsl / scan_ballot.comp.glsl (the top pass on subgroup ops),
//             workgroup.glsl (penumbraScanWorkgroupExclusive/Inclusive/Reduce for your own
//             kernels; hook PENUMBRA_SCAN_GROUP_SIZE, see that file), scan_shared.h (constants).
//
// Algorithm: reduce-then-scan over tiles of items_per_thread consecutive elements (default 16),
// one tile per invocation, loaded as uvec4s and reduced or scanned serially in registers.
//   level L with count c > group_size * items_per_thread (one group's worth):
//     reduce pass: one sum per tile into scratch (reads c, writes c / items);
//     level L + 1 scans those tile sums exclusively, in place;
//     scan pass:   each tile = its scanned offset + its serial scan (reads c, writes c).
//   the top level (c <= one group's worth): one work group, one workgroup scan.
// The bulk passes have no barrier and no shared memory — on llvmpipe (SIMD over invocations, a
// coroutine switch per barrier) that is most of the speed — and each level shrinks the data
// items_per_thread-fold, so the levels above the first add ~7% of its traffic. GL_MAX_SHADER_STORAGE_BLOCK_SIZE
// (llvmpipe: 128 MiB = 2^25 uints) bounds one binding, so larger inputs run in windows; the top
// pass of each window carries the running total to the next through a scratch word, and a ragged
// last 1-3 elements run as their own window so the uvec4 kernels only see whole uvec4s. Grids of
// more than GL_MAX_COMPUTE_WORK_GROUP_COUNT[0] groups are folded into 2D (detail::foldDispatch).
//
// GL state contract of Scanner::scan / exclusive / inclusive (n > 0):
//   * the first dispatch is preceded by glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT), so shader
//     writes you made to the input in earlier dispatches/draws (SSBO, image or atomic-counter
//     stores) are visible; writes through glBufferSubData / copies / clears need nothing;
//   * the scanner's compute dispatches are separated by the same barrier, and none follows the
//     last one: before you read the output issue the barrier for how you read it —
//     GL_SHADER_STORAGE_BARRIER_BIT for SSBO reads in shaders, GL_BUFFER_UPDATE_BARRIER_BIT for
//     glGetBufferSubData / mapping, GL_COMMAND_BARRIER_BIT for indirect draws/dispatches,
//     GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT / GL_ELEMENT_ARRAY_BARRIER_BIT for vertex or index pulls,
//     GL_UNIFORM_BARRIER_BIT for UBO reads;
//   * it changes and does not restore: the current program (left at 0, glUseProgram(0)); the
//     indexed GL_SHADER_STORAGE_BUFFER bindings 0, 1, 2, 3, 4 (PENUMBRA_SCAN_BINDING_*; left
//     unbound) and the generic GL_SHADER_STORAGE_BUFFER binding (left 0). Nothing else (no VAO,
//     framebuffer, texture, image or uniform-block state); uniforms live in its own programs;
//   * n == 0 returns at once and touches no GL state (buffer names are not checked then).
//   Scratch (tile sums, the window carry) lives in one buffer the Scanner owns; scan() grows it
//   when needed — call reserve(n) at load time to keep allocations out of frames. Constructing a
//   Scanner that picks a subgroup path runs a small check scan (its own buffers; the same state
//   changes as a scan).
//
// Errors (penumbra::Error naming the value): a name that is not a buffer object, a buffer with
// no storage (GL_BUFFER_SIZE 0), an offset that is not a multiple of 4, a range past
// GL_BUFFER_SIZE, n > kScanMaxElements, input and output ranges in the same buffer that overlap
// without being identical, bad ScanOptions (group size not a power of two in [32, driver maximum],
// items per thread not a multiple of 4 in [4, 64], window_elements below one group's worth).
#ifndef PENUMBRA_SCAN_HPP
#define PENUMBRA_SCAN_HPP

#include "penumbra/detail/dispatch.hpp"
#include "penumbra/detail/shared.hpp"
#include "penumbra/error.hpp"
#include "penumbra/buffer_range.hpp"

// scan_shared.h holds only macros. It lives with the shaders; with shaders/ on the include path
// it is found there, otherwise beside this header in the source tree.
#if defined(__has_include) && __has_include(<penumbra/scan/scan_shared.h>)
#include <penumbra/scan/scan_shared.h>
#else
#include "../../shaders/penumbra/scan/scan_shared.h"
#endif

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace penumbra {

struct ScanBindings {};

enum class ScanKind { Exclusive, Inclusive };

inline const char* scanKindName(ScanKind kind) { return kind == ScanKind::Inclusive ? "inclusive" : "exclusive"; }

/// How the top pass's workgroup scan combines invocations (Scanner::subgroupMode()).
enum class ScanSubgroups { None, Khr, Ballot };

inline const char* scanSubgroupsName(ScanSubgroups mode) {
    return mode == ScanSubgroups::Khr      ? "GL_KHR_shader_subgroup_arithmetic"
           : mode == ScanSubgroups::Ballot ? "GL_ARB_shader_ballot"
                                           : "shared memory";
}

/// The largest n a scan accepts: results are 32-bit offsets, so more elements than a uint can
/// count is never meaningful (and needs a buffer over 16 GiB).
inline constexpr uint64_t kScanMaxElements = 0xFFFFFFFFull;

/// Value-initialised = defaults (0 = default for every number).
struct ScanOptions {
    uint32_t group_size = 0;        ///< invocations per work group, power of two in [32, 1024]; 0 = 256
    uint32_t items_per_thread = 0;  ///< uints per invocation (tile), multiple of 4 in [4, 64]; 0 = 16
    bool allow_subgroups = true;    ///< false forces the shared-memory workgroup scan
    /// At most this many elements per binding window (rounded down to whole groups' worth of
    /// tiles); 0 = as many as GL_MAX_SHADER_STORAGE_BLOCK_SIZE allows. Mainly for testing the
    /// carry between windows.
    uint64_t window_elements = 0;
};

/// Driver limits a plan respects. Value-initialised = the GL 4.5 guaranteed minima (and the
/// largest allowed binding alignment), which every driver satisfies.
struct ScanLimits {
    uint64_t max_binding_bytes = uint64_t(1) << 27;          ///< GL_MAX_SHADER_STORAGE_BLOCK_SIZE
    uint32_t binding_alignment = 256;                        ///< GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT
    uint64_t max_groups_x = detail::kMaxGroupsPerDimension;  ///< GL_MAX_COMPUTE_WORK_GROUP_COUNT[0]
    uint64_t max_groups_y = detail::kMaxGroupsPerDimension;  ///< GL_MAX_COMPUTE_WORK_GROUP_COUNT[1]
    uint32_t max_group_size = 1024;  ///< min(GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS, ..._SIZE[0])
};

/// One level of one window: `count` elements in `tiles` tiles (one per invocation).
struct ScanLevel {
    uint64_t count = 0;
    uint64_t tiles = 0;          ///< ceil(count / items_per_thread)
    detail::DispatchGrid grid;   ///< ceil(tiles / group_size) groups, folded; top level: 1 group
    bool top = false;            ///< the last level: one work group scans it whole
    /// Byte offset in the scratch buffer of this level's tile sums (not for the top level): the
    /// reduce pass writes them, the next level scans them in place, the scan pass reads them back
    /// as the tiles' offsets.
    uint64_t partials_offset = 0;
};

/// Everything the GPU scan of n elements will do, computed without GL.
///
/// Windows: the first main_windows windows hold n - tail_elements elements in chunks of
/// window_elements (the last may be shorter); when n > 4 is not a multiple of 4, one more window
/// holds the last tail_elements (1 to 3) elements, so every main window's count is a multiple of 4
/// and the uvec4 kernels never meet a partial uvec4. Window w > 0 starts from the running total
/// window w - 1 left in the carry word (scratch offset 0).
struct ScanPlan {
    uint64_t n = 0;
    uint32_t group_size = 0;        ///< resolved options
    uint32_t items_per_thread = 0;
    uint64_t top_elements = 0;      ///< group_size * items_per_thread: what the top pass scans at most
    uint32_t alignment = 0;         ///< lcm(16, binding_alignment): binding offsets, scratch arrays
    uint64_t window_elements = 0;   ///< elements per main window, a multiple of top_elements
    uint64_t main_windows = 0;      ///< ceil((n - tail_elements) / window_elements)
    uint64_t tail_elements = 0;     ///< 0, or n % 4 when n > 4 and n % 4 != 0
    uint64_t windows = 0;           ///< main_windows + (tail_elements != 0)
    std::vector<ScanLevel> levels;       ///< a full main window (the first); levels.back().top
    std::vector<ScanLevel> last_levels;  ///< the last main window (== levels when main_windows == 1)
    std::vector<ScanLevel> tail_levels;  ///< the tail window: one top level, or empty
    uint64_t scratch_bytes = 0;     ///< carry word (at 0, padded to alignment) + tile-sum arrays
    uint64_t dispatches = 0;        ///< compute dispatches in total

    /// First element of window w.
    uint64_t windowFirst(uint64_t w) const { return w < main_windows ? w * window_elements : n - tail_elements; }
    /// The levels of window w.
    const std::vector<ScanLevel>& windowLevels(uint64_t w) const {
        return w >= main_windows ? tail_levels : w + 1 == main_windows ? last_levels : levels;
    }
};

namespace detail {

inline constexpr uint32_t kScanDefaultGroupSize = PENUMBRA_SCAN_DEFAULT_GROUP_SIZE;
inline constexpr uint32_t kScanDefaultItemsPerThread = PENUMBRA_SCAN_DEFAULT_ITEMS_PER_THREAD;
inline constexpr uint32_t kScanMinGroupSize = PENUMBRA_SCAN_MIN_GROUP_SIZE;
inline constexpr uint32_t kScanMaxGroupSize = PENUMBRA_SCAN_MAX_GROUP_SIZE;
inline constexpr uint32_t kScanMaxItemsPerThread = PENUMBRA_SCAN_MAX_ITEMS_PER_THREAD;
static_assert(kScanDefaultGroupSize >= kScanMinGroupSize && kScanDefaultGroupSize <= kScanMaxGroupSize);
static_assert(kScanDefaultItemsPerThread % 4 == 0 && kScanDefaultItemsPerThread <= kScanMaxItemsPerThread);
// workgroup.glsl keeps one uint per invocation plus the total in shared memory, and at most one
// segment or subgroup sum per invocation: (2 * 1024 + 1) * 4 bytes fits GL's 32 KiB minimum.
static_assert((2 * kScanMaxGroupSize + 1) * 4 <= 32768);

inline constexpr bool isPowerOfTwo(uint64_t x) { return x != 0 && (x & (x - 1)) == 0; }
inline constexpr uint64_t alignUp(uint64_t x, uint64_t a) { return divUp(x, a) * a; }
inline uint64_t gcd64(uint64_t a, uint64_t b) {
    while (b) a = std::exchange(b, a % b);
    return a;
}
/// lcm(16, binding alignment): uvec4 views need 16-byte-aligned binding offsets as well.
inline uint64_t scanAlignment(const ScanLimits& limits) {
    return 16 / gcd64(16, limits.binding_alignment) * limits.binding_alignment;
}

/// ScanOptions with defaults filled in; throws penumbra::Error naming a bad value.
inline ScanOptions resolveScanOptions(const ScanOptions& options, const ScanLimits& limits) {
    ScanOptions r = options;
    if (r.group_size == 0) r.group_size = kScanDefaultGroupSize;
    if (r.items_per_thread == 0) r.items_per_thread = kScanDefaultItemsPerThread;
    const uint32_t max_group = std::min<uint32_t>(kScanMaxGroupSize, limits.max_group_size);
    PENUMBRA_CHECK(isPowerOfTwo(r.group_size) && r.group_size >= kScanMinGroupSize && r.group_size <= max_group,
                   "penumbra: ScanOptions::group_size ", r.group_size, " must be a power of two in [",
                   kScanMinGroupSize, ", ", max_group, "]");
    PENUMBRA_CHECK(r.items_per_thread % 4 == 0 && r.items_per_thread >= 4 &&
                       r.items_per_thread <= kScanMaxItemsPerThread,
                   "penumbra: ScanOptions::items_per_thread ", r.items_per_thread,
                   " must be a multiple of 4 in [4, ", kScanMaxItemsPerThread, "]");
    return r;
}

/// Levels of one window of `count` elements; the first tile-sum array starts at `offset` bytes,
/// `*end_offset` receives the end of the last one.
inline std::vector<ScanLevel> planScanLevels(uint64_t count, uint64_t items, uint64_t group_size,
                                             uint64_t alignment, const ScanLimits& limits, uint64_t offset,
                                             uint64_t* end_offset) {
    std::vector<ScanLevel> levels;
    while (count > 0) {
        ScanLevel level;
        level.count = count;
        level.tiles = divUp(count, items);
        level.top = count <= items * group_size;
        level.grid = foldDispatch(level.top ? 1 : divUp(level.tiles, group_size), limits.max_groups_x,
                                  limits.max_groups_y);
        if (!level.top) {
            level.partials_offset = offset;
            offset += alignUp(level.tiles * 4, alignment);
        }
        levels.push_back(level);
        if (level.top) break;
        count = level.tiles;
    }
    if (end_offset) *end_offset = offset;
    return levels;
}

}  // namespace detail

/// Pure setup: what a scan of n elements does under `options` and `limits` (no GL). Throws
/// penumbra::Error for n > kScanMaxElements, bad options, or limits too small for one group.
inline ScanPlan planScan(uint64_t n, const ScanOptions& options = {}, const ScanLimits& limits = {}) {
    PENUMBRA_CHECK(n <= kScanMaxElements, "penumbra: scan of n = ", n, " elements exceeds kScanMaxElements = ",
                   kScanMaxElements);
    PENUMBRA_CHECK(limits.binding_alignment > 0 && limits.binding_alignment % 4 == 0,
                   "penumbra: ScanLimits::binding_alignment ", limits.binding_alignment,
                   " is not a positive multiple of 4");
    const ScanOptions resolved = detail::resolveScanOptions(options, limits);
    ScanPlan plan;
    plan.n = n;
    plan.group_size = resolved.group_size;
    plan.items_per_thread = resolved.items_per_thread;
    plan.top_elements = uint64_t(resolved.group_size) * resolved.items_per_thread;
    plan.alignment = static_cast<uint32_t>(detail::scanAlignment(limits));
    // A window's binding starts up to alignment - 4 bytes before its first element.
    const uint64_t slack = plan.alignment / 4 - 1;
    const uint64_t fit = limits.max_binding_bytes / 4 > slack ? limits.max_binding_bytes / 4 - slack : 0;
    uint64_t window = fit / plan.top_elements * plan.top_elements;
    PENUMBRA_CHECK(window > 0, "penumbra: GL_MAX_SHADER_STORAGE_BLOCK_SIZE ", limits.max_binding_bytes,
                   " cannot hold one scan group's ", plan.top_elements, " elements");
    if (resolved.window_elements != 0) {
        const uint64_t wanted = resolved.window_elements / plan.top_elements * plan.top_elements;
        PENUMBRA_CHECK(wanted > 0, "penumbra: ScanOptions::window_elements ", resolved.window_elements,
                       " is smaller than one group's ", plan.top_elements, " elements");
        window = std::min(window, wanted);
    }
    plan.window_elements = window;
    if (n == 0) return plan;
    plan.tail_elements = (n > 4 && n % 4 != 0) ? n % 4 : 0;
    const uint64_t main = n - plan.tail_elements;
    plan.main_windows = detail::divUp(main, window);
    plan.windows = plan.main_windows + (plan.tail_elements != 0);
    const uint64_t items = plan.items_per_thread, group = plan.group_size;
    uint64_t end = 0;
    plan.levels = detail::planScanLevels(std::min(main, window), items, group, plan.alignment, limits, plan.alignment,
                                         &end);
    plan.last_levels = plan.main_windows == 1
                           ? plan.levels
                           : detail::planScanLevels(main - (plan.main_windows - 1) * window, items, group,
                                                    plan.alignment, limits, plan.alignment, nullptr);
    if (plan.tail_elements) {
        plan.tail_levels =
            detail::planScanLevels(plan.tail_elements, items, group, plan.alignment, limits, plan.alignment, nullptr);
    }
    // Scratch: the carry word (windows > 1) and the tile-sum arrays (levels > 1); the first window
    // is the largest, so its layout bounds every window's.
    plan.scratch_bytes = (plan.levels.size() > 1 || plan.windows > 1) ? end : 0;
    PENUMBRA_CHECK(plan.scratch_bytes <= limits.max_binding_bytes, "penumbra: scan scratch of ", plan.scratch_bytes,
                   " bytes exceeds GL_MAX_SHADER_STORAGE_BLOCK_SIZE ", limits.max_binding_bytes);
    for (uint64_t w = 0; w < plan.windows; ++w) plan.dispatches += 2 * plan.windowLevels(w).size() - 1;
    return plan;
}

/// CPU twin of the GPU scan, std::exclusive_scan / std::inclusive_scan-compatible on uint32_t
/// (wrap-around mod 2^32 included). input: n uints; output: n uints, may equal input (in place);
/// both may be null when n == 0. Partially overlapping ranges throw penumbra::Error.
inline void scanCpu(const uint32_t* input, uint32_t* output, size_t n, ScanKind kind) {
    if (n == 0) return;
    PENUMBRA_CHECK(input && output, "penumbra: scanCpu of n = ", n, " elements got a null ",
                   input ? "output" : "input", " pointer");
    const std::less<const uint32_t*> before;
    const bool overlap = before(input, output + n) && before(output, input + n);
    PENUMBRA_CHECK(!overlap || input == output, "penumbra: scanCpu input and output ranges of ", n,
                   " elements overlap without being the same range (offset ", output - input, " elements)");
    uint32_t run = 0;
    if (kind == ScanKind::Exclusive) {
        for (size_t i = 0; i < n; ++i) {
            const uint32_t x = input[i];  // read before the write: in place is fine
            output[i] = run;
            run += x;
        }
    } else {
        for (size_t i = 0; i < n; ++i) {
            run += input[i];
            output[i] = run;
        }
    }
}

}  // namespace penumbra

// ---- GL execution (Scanner) -------------------------------------------------------------------
#ifndef PENUMBRA_SCAN_NO_GL

#include "penumbra/gl/gl.hpp"
#include "penumbra/gl/shader.hpp"

#include <cstring>

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
    PENUMBRA_CHECK(limits.max_binding_bytes > 0 && limits.binding_alignment > 0 && limits.max_groups_x > 0 &&
                       limits.max_groups_y > 0,
                   "penumbra: the driver reported unusable compute limits (is a GL 4.5 context current?)");
    return limits;
}

/// Scans uint buffer ranges on the GPU (see the summary at the top of this file). Owns its
/// programs and a scratch buffer: RAII, movable, not copyable; create, use and destroy it with
/// the same GL context current. A moved-from Scanner may only be destroyed or assigned to.
class Scanner {
public:
    /// Needs a current GL 4.5 context; queries the limits and compiles six programs (reduce, scan
    /// and top passes; uvec4 and scalar addressing). Throws penumbra::Error for bad options or
    /// shader errors.
    explicit Scanner(const ScanOptions& options = {}, const ShaderLibrary& library = ShaderLibrary::embedded())
        : limits_(queryScanLimits()) {
        options_ = detail::resolveScanOptions(options, limits_);
        planScan(0, options_, limits_);  // validates window_elements against the limits
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
        gl::checkErrors("penumbra::Scanner construction");
    }

    // TEMPORARY shim until the engine-grade scanner lands (h/scan).
    Scanner(const ScanOptions& options, const ShaderLibrary& library, const ScanBindings&) : Scanner(options, library) {}
    Status exclusive(const BufferRange& in, const BufferRange& out, uint64_t n) {
        exclusive(in.buffer, in.offset, out.buffer, out.offset, n);
        return Status::Ok;
    }
    Scanner(Scanner&& other) noexcept { *this = std::move(other); }
    Scanner& operator=(Scanner&& other) noexcept {
        if (this != &other) {
            releaseScratch();
            options_ = other.options_;
            limits_ = other.limits_;
            subgroups_ = other.subgroups_;
            for (int p = 0; p < kPasses; ++p) {
                for (int v = 0; v < 2; ++v) kernels_[p][v] = std::move(other.kernels_[p][v]);
            }
            scratch_ = std::exchange(other.scratch_, 0);
            scratch_capacity_ = std::exchange(other.scratch_capacity_, 0);
        }
        return *this;
    }
    Scanner(const Scanner&) = delete;
    Scanner& operator=(const Scanner&) = delete;
    ~Scanner() { releaseScratch(); }

    /// Scratch bytes a scan of n elements needs (0 when one group covers n). Pure arithmetic.
    size_t scratchBytes(uint64_t n) const { return static_cast<size_t>(plan(n).scratch_bytes); }
    /// The plan scan(n) executes (windows, levels, grids, scratch). Pure arithmetic.
    ScanPlan plan(uint64_t n) const { return planScan(n, options_, limits_); }
    /// Grows the scratch buffer to scratchBytes(n) now (scan() would do it on demand).
    void reserve(uint64_t n) { reserveBytes(scratchBytes(n)); }

    /// Scans n uints starting at input_offset_bytes of `input` into `output` at
    /// output_offset_bytes (same buffer and offset = in place). See the GL state contract above.
    void scan(ScanKind kind, GLuint input, size_t input_offset_bytes, GLuint output, size_t output_offset_bytes,
              uint64_t n) {
        if (n == 0) return;
        const ScanPlan p = plan(n);  // checks n
        checkRange("input", input, input_offset_bytes, n);
        checkRange("output", output, output_offset_bytes, n);
        if (input == output && input_offset_bytes != output_offset_bytes) {
            const uint64_t bytes = n * 4;
            const uint64_t a = input_offset_bytes, b = output_offset_bytes;
            PENUMBRA_CHECK(a + bytes <= b || b + bytes <= a, "penumbra: scan of n = ", n, " elements in buffer ",
                           input, ": input offset ", a, " and output offset ", b,
                           " overlap without being equal (in place needs equal offsets)");
        }
        reserveBytes(p.scratch_bytes);
        // Both shifts are the same for every window (main windows start whole groups' worth of
        // elements apart, multiples of 16 bytes; the tail window has a count below 4 anyway).
        const bool user_quads = shiftOf(input_offset_bytes) % 4 == 0 && shiftOf(output_offset_bytes) % 4 == 0;
        for (uint64_t w = 0; w < p.windows; ++w) {
            const std::vector<ScanLevel>& levels = p.windowLevels(w);
            const uint64_t first = p.windowFirst(w);
            const Range in{input, input_offset_bytes + first * 4};
            const Range out{output, output_offset_bytes + first * 4};
            const size_t top = levels.size() - 1;
            // uvec4 addressing needs whole uvec4s: shifts and count multiples of 4 (the scratch
            // arrays start aligned, so only their counts matter).
            auto quads = [&](size_t l) { return (l == 0 ? user_quads : true) && levels[l].count % 4 == 0; };
            auto data = [&](size_t l) { return l == 0 ? in : Range{scratch_, levels[l - 1].partials_offset}; };
            // Up: every level below the top leaves one sum per tile for the level above.
            for (size_t l = 0; l < top; ++l) {
                dispatch(kReduce, quads(l), levels[l], data(l), data(l), levels[l].partials_offset / 4, 0);
            }
            // Top: one group, exclusive in place (or, with one level, straight to the output with
            // the caller's kind), taking the previous window's carry and leaving the next one's.
            uint32_t flags = 0;
            if (top == 0 && kind == ScanKind::Inclusive) flags |= PENUMBRA_SCAN_FLAG_INCLUSIVE;
            if (w > 0) flags |= PENUMBRA_SCAN_FLAG_READ_OFFSETS;
            if (w + 1 < p.windows) flags |= PENUMBRA_SCAN_FLAG_WRITE_CARRY;
            dispatch(kTop, quads(top), levels[top], data(top), top == 0 ? out : data(top), 0, flags);
            // Down: each level adds its tiles' scanned offsets.
            for (size_t l = top; l-- > 0;) {
                const uint32_t down_flags = (l == 0 && kind == ScanKind::Inclusive) ? PENUMBRA_SCAN_FLAG_INCLUSIVE : 0;
                dispatch(kScan, quads(l), levels[l], data(l), l == 0 ? out : data(l), levels[l].partials_offset / 4,
                         down_flags);
            }
        }
        for (GLuint b = 0; b < PENUMBRA_SCAN_BINDING_COUNT; ++b) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b, 0);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        glUseProgram(0);
    }
    void exclusive(GLuint input, size_t input_offset_bytes, GLuint output, size_t output_offset_bytes, uint64_t n) {
        scan(ScanKind::Exclusive, input, input_offset_bytes, output, output_offset_bytes, n);
    }
    void inclusive(GLuint input, size_t input_offset_bytes, GLuint output, size_t output_offset_bytes, uint64_t n) {
        scan(ScanKind::Inclusive, input, input_offset_bytes, output, output_offset_bytes, n);
    }

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
    GLuint scratchBuffer() const { return scratch_; }
    size_t scratchCapacity() const { return scratch_capacity_; }

private:
    struct Kernel {
        gl::Program program;
        GLint count = -1, input_shift = -1, output_shift = -1, partials_index = -1, carry_index = -1, flags = -1;
    };
    struct Range {
        GLuint buffer;
        uint64_t offset;  ///< byte offset of element 0
    };
    static constexpr int kReduce = 0, kScan = 1, kTop = 2, kPasses = 3;

    ScanOptions options_;
    ScanLimits limits_;
    ScanSubgroups subgroups_ = ScanSubgroups::None;
    Kernel kernels_[kPasses][2];  ///< [pass][addressing: scalar, uvec4]
    GLuint scratch_ = 0;
    size_t scratch_capacity_ = 0;

    uint32_t shiftOf(uint64_t offset_bytes) const {
        return static_cast<uint32_t>(offset_bytes % detail::scanAlignment(limits_) / 4);
    }

    void buildKernel(int pass, int vec4, const char* key, const ShaderLibrary& library) {
        static const char* const kPassNames[kPasses] = {"PENUMBRA_SCAN_PASS_REDUCE", "PENUMBRA_SCAN_PASS_SCAN",
                                                        "PENUMBRA_SCAN_PASS_TOP"};
        const ShaderDefines defines = {{"PENUMBRA_SCAN_PASS", kPassNames[pass]},
                                       {"PENUMBRA_SCAN_GROUP_SIZE", std::to_string(options_.group_size)},
                                       {"PENUMBRA_SCAN_ITEMS_PER_THREAD", std::to_string(options_.items_per_thread)},
                                       {"PENUMBRA_SCAN_VEC4", vec4 ? "1" : "0"}};
        Kernel& k = kernels_[pass][vec4];
        k.program = gl::buildComputeProgram(key, defines, library);
        k.count = k.program.uniform("penumbraScanCount");
        k.input_shift = k.program.uniform("penumbraScanInputShift");
        k.output_shift = k.program.uniform("penumbraScanOutputShift");
        k.partials_index = k.program.uniform("penumbraScanPartialsIndex");
        k.carry_index = k.program.uniform("penumbraScanCarryIndex");
        k.flags = k.program.uniform("penumbraScanFlags");
    }

    void buildTopKernels(const ShaderLibrary& library) {
        const char* key = subgroups_ == ScanSubgroups::Khr      ? "penumbra/scan/scan_subgroups.comp.glsl"
                          : subgroups_ == ScanSubgroups::Ballot ? "penumbra/scan/scan_ballot.comp.glsl"
                                                                : "penumbra/scan/scan.comp.glsl";
        for (int vec4 = 0; vec4 < 2; ++vec4) buildKernel(kTop, vec4, key, library);
    }

    // Scans one group's worth + 2 * items + 7 elements of a fixed pattern (reduce, top, scan, the
    // tail window's carry) into an aligned and a misaligned range (uvec4 and scalar kernels) and
    // compares with scanCpu.
    bool selfCheck() {
        const uint64_t n = (uint64_t(options_.group_size) + 2) * options_.items_per_thread + 7;
        std::vector<uint32_t> values(n), want(n), got(n);
        for (uint64_t i = 0; i < n; ++i) values[i] = static_cast<uint32_t>(i * 2654435761u + 12345u);
        scanCpu(values.data(), want.data(), n, ScanKind::Exclusive);
        GLuint buffers[2] = {0, 0};
        glCreateBuffers(2, buffers);
        glNamedBufferStorage(buffers[0], static_cast<GLsizeiptr>(n * 4), values.data(), 0);
        glNamedBufferStorage(buffers[1], static_cast<GLsizeiptr>(n * 4 + 4), nullptr, 0);
        bool ok = true;
        for (size_t offset : {size_t(0), size_t(4)}) {
            scan(ScanKind::Exclusive, buffers[0], 0, buffers[1], offset, n);
            glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
            glGetNamedBufferSubData(buffers[1], static_cast<GLintptr>(offset), static_cast<GLsizeiptr>(n * 4),
                                    got.data());
            ok = ok && got == want;
        }
        glDeleteBuffers(2, buffers);
        return ok;
    }

    static void checkRange(const char* what, GLuint buffer, size_t offset, uint64_t n) {
        PENUMBRA_CHECK(buffer != 0 && glIsBuffer(buffer), "penumbra: scan ", what, " buffer ", buffer,
                       " is not a buffer object");
        GLint64 size = 0;
        glGetNamedBufferParameteri64v(buffer, GL_BUFFER_SIZE, &size);
        PENUMBRA_CHECK(size > 0, "penumbra: scan ", what, " buffer ", buffer,
                       " has no storage (GL_BUFFER_SIZE 0; allocate it with glNamedBufferStorage/Data)");
        PENUMBRA_CHECK(offset % 4 == 0, "penumbra: scan ", what, " offset ", offset,
                       " bytes is not a multiple of 4");
        const uint64_t bytes = n * 4, total = static_cast<uint64_t>(size);
        PENUMBRA_CHECK(offset <= total && bytes <= total - offset, "penumbra: scan ", what, " range of n = ", n,
                       " elements at offset ", offset, " (", bytes, " bytes) exceeds buffer ", buffer,
                       "'s GL_BUFFER_SIZE ", total);
    }

    void reserveBytes(uint64_t bytes) {
        if (bytes <= scratch_capacity_) return;
        releaseScratch();
        glCreateBuffers(1, &scratch_);
        while (glGetError() != GL_NO_ERROR) {
        }
        glNamedBufferStorage(scratch_, static_cast<GLsizeiptr>(bytes), nullptr, 0);
        const GLenum error = glGetError();
        if (error != GL_NO_ERROR) {
            releaseScratch();
            ::penumbra::detail::fail("penumbra: allocating ", bytes, " bytes of scan scratch failed with ",
                                     gl::errorName(error));
        }
        scratch_capacity_ = static_cast<size_t>(bytes);
    }
    void releaseScratch() {
        if (scratch_) glDeleteBuffers(1, &scratch_);
        scratch_ = 0;
        scratch_capacity_ = 0;
    }

    // Binds `count` elements of `data` from an aligned offset at or before it (uint view at
    // `index`, uvec4 view at `index_vec4` too when `vec4`) and sets the element shift uniform.
    void bindData(GLuint index, GLuint index_vec4, const Range& data, uint64_t count, bool vec4, GLint shift_location,
                  GLuint program) const {
        const uint64_t shift = shiftOf(data.offset);
        const uint64_t base = data.offset - shift * 4;
        const GLsizeiptr bytes = static_cast<GLsizeiptr>((shift + count) * 4);
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, index, data.buffer, static_cast<GLintptr>(base), bytes);
        if (vec4) glBindBufferRange(GL_SHADER_STORAGE_BUFFER, index_vec4, data.buffer, static_cast<GLintptr>(base), bytes);
        if (shift_location >= 0) glProgramUniform1ui(program, shift_location, static_cast<GLuint>(shift));
    }

    // One pass over `level`: binds the data ranges and the scratch, sets the uniforms, and
    // dispatches after a GL_SHADER_STORAGE_BARRIER_BIT barrier — the first one makes the caller's
    // shader writes to the input visible, later ones order the passes; none follows the last.
    void dispatch(int pass, bool vec4, const ScanLevel& level, const Range& in, const Range& out,
                  uint64_t partials_index, uint32_t flags) {
        const Kernel& k = kernels_[pass][vec4 ? 1 : 0];
        const GLuint program = k.program.id();
        bindData(PENUMBRA_SCAN_BINDING_INPUT, PENUMBRA_SCAN_BINDING_INPUT_VEC4, in, level.count, vec4, k.input_shift,
                 program);
        if (pass != kReduce) {
            bindData(PENUMBRA_SCAN_BINDING_OUTPUT, PENUMBRA_SCAN_BINDING_OUTPUT_VEC4, out, level.count, vec4,
                     k.output_shift, program);
        }
        if (scratch_) {
            glBindBufferRange(GL_SHADER_STORAGE_BUFFER, PENUMBRA_SCAN_BINDING_PARTIALS, scratch_, 0,
                              static_cast<GLsizeiptr>(scratch_capacity_));
        }
        if (k.count >= 0) glProgramUniform1ui(program, k.count, static_cast<GLuint>(level.count));
        if (k.partials_index >= 0) glProgramUniform1ui(program, k.partials_index, static_cast<GLuint>(partials_index));
        if (k.carry_index >= 0) glProgramUniform1ui(program, k.carry_index, 0u);
        if (k.flags >= 0) glProgramUniform1ui(program, k.flags, flags);
        glUseProgram(program);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        glDispatchCompute(level.grid.x, level.grid.y, 1);
    }
};

}  // namespace penumbra

#endif  // PENUMBRA_SCAN_NO_GL

#endif
