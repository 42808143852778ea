// penumbra — prefix sums (scan) of uint buffers: pure setup, the dispatch plan, and the CPU twin.
//
// sintorn2008 §3.1 turns per-texel list counts into list offsets with a scan [Harris, Sengupta,
// Owens 2007, "Parallel Prefix Sum (Scan) with CUDA", GPU Gems 3 ch. 39]. This block is that scan
// for any uint buffer: out[i] = in[0] + ... + in[i-1] (exclusive) or + in[i] (inclusive), mod 2^32,
// exactly what std::exclusive_scan / std::inclusive_scan give on uint32_t.
//
// Integration summary
//   this header: no GL at all (include it anywhere). planScan() is the FidelityFX-style setup: for
//             n elements (and the kind and byte offsets of the two ranges) it returns the windows
//             and levels, the scratch size, and the dispatch list — per dispatch the kernel (pass,
//             scalar or uvec4 addressing), the grid, the PenumbraScanConstants block
//             (scan_shared.h) and its offset in the constants buffer, and which byte ranges of the
//             caller's input/output buffers and of the scratch buffer are bound where. An engine
//             with its own RHI records those dispatches itself (see "Recording a plan" below).
//             scanCpu: the CPU twin (also a fallback). PENUMBRA_SCAN_NO_GL is no longer needed
//             (harmless if defined): the GL executor lives in penumbra/gl/scan.hpp.
//   GL executor: penumbra::Scanner in penumbra/gl/scan.hpp (compiles the kernels, owns scratch and
//             constants buffers, records the plan with GL 4.5 calls; per-frame scan() allocates,
//             queries and throws nothing).
//   GPU code: shaders/penumbra/scan/scan.comp.glsl (reduce, scan and top passes),
//             scan_subgroups.comp.glsl / scan_ballot.comp.glsl (the top pass on subgroup ops),
//             workgroup.glsl (penumbraScanWorkgroupExclusive/Inclusive/Reduce for your own
//             kernels; hook PENUMBRA_SCAN_GROUP_SIZE, checked against gl_WorkGroupSize),
//             scan_shared.h (constants, bindings, PenumbraScanConstants).
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
// pass of each window carries the running total to the next through two alternating scratch
// words (window w reads word w % 2, writes word (w + 1) % 2), and a ragged last 1-3 elements run
// as their own window so the uvec4 kernels only see whole uvec4s. Grids of more than
// GL_MAX_COMPUTE_WORK_GROUP_COUNT[0] groups are folded into 2D (detail::foldDispatch).
//
// Recording a plan (what Scanner does; tests/scan_test.cpp replays a plan with raw GL calls):
//   once: compile scan.comp.glsl for each (pass, vec4) the plan uses, with PENUMBRA_SCAN_PASS,
//         PENUMBRA_SCAN_GROUP_SIZE = plan.group_size, PENUMBRA_SCAN_ITEMS_PER_THREAD =
//         plan.items_per_thread, PENUMBRA_SCAN_VEC4 = 0/1 (the top pass may use
//         scan_subgroups/scan_ballot.comp.glsl instead); a scratch buffer of plan.scratch_bytes
//         (contents need no initialisation) and a uniform buffer of plan.constants_bytes.
//   per scan: upload plan.constants[i] at plan.dispatch_list[i].constants.offset (stride
//         plan.constants_stride, a multiple of ScanLimits::uniform_alignment); then for every
//         dispatch, in order: bind its ranges (input/output also at the *_VEC4 bindings when
//         dispatch.vec4; a range with buffer ScanBuffer::None binds nothing), bind the program,
//         memory barrier (GL_SHADER_STORAGE_BARRIER_BIT, or your RHI's UAV barrier), dispatch
//         grid.x * grid.y * 1 groups. Offsets of ScanBuffer::Input / Output ranges are absolute
//         byte offsets in your buffers (they start up to alignment - 4 bytes before your range:
//         binding offsets must be aligned; the shift constants skip the slack).
#ifndef PENUMBRA_SCAN_HPP
#define PENUMBRA_SCAN_HPP

#include "penumbra/detail/dispatch.hpp"
#include "penumbra/detail/shared.hpp"
#include "penumbra/error.hpp"

// scan_shared.h lives with the shaders; with shaders/ on the include path it is found there,
// otherwise beside this header in the source tree.
#if defined(__has_include) && __has_include(<penumbra/scan/scan_shared.h>)
#include <penumbra/scan/scan_shared.h>
#else
#include "../../shaders/penumbra/scan/scan_shared.h"
#endif

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <type_traits>
#include <utility>
#include <vector>

namespace penumbra {

static_assert(sizeof(shared::PenumbraScanConstants) == 32, "PenumbraScanConstants: 8 uints, std140 = C++ layout");
static_assert(std::is_trivially_copyable_v<shared::PenumbraScanConstants>);
static_assert(offsetof(shared::PenumbraScanConstants, carry_out_index) == 20 &&
              offsetof(shared::PenumbraScanConstants, flags) == 24);

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
/// largest allowed binding alignments), which every driver satisfies.
struct ScanLimits {
    uint64_t max_binding_bytes = uint64_t(1) << 27;          ///< GL_MAX_SHADER_STORAGE_BLOCK_SIZE
    uint32_t binding_alignment = 256;                        ///< GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT
    uint64_t max_groups_x = detail::kMaxGroupsPerDimension;  ///< GL_MAX_COMPUTE_WORK_GROUP_COUNT[0]
    uint64_t max_groups_y = detail::kMaxGroupsPerDimension;  ///< GL_MAX_COMPUTE_WORK_GROUP_COUNT[1]
    uint32_t max_group_size = 1024;  ///< min(GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS, ..._SIZE[0])
    uint32_t uniform_alignment = 256;  ///< GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT (constants stride)
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

/// Most levels one window can have: counts up to 2^32 shrink at least 4-fold per level until they
/// fit one group's worth (>= 32 * 4 elements), i.e. 13 levels plus the top.
inline constexpr size_t kScanMaxLevels = 16;

/// The levels of one window: a fixed-capacity list (planning allocates nothing).
class ScanLevels {
public:
    size_t size() const { return size_; }
    bool empty() const { return size_ == 0; }
    const ScanLevel& operator[](size_t i) const { return levels_[i]; }
    const ScanLevel& back() const { return levels_[size_ - 1]; }
    const ScanLevel* begin() const { return levels_.data(); }
    const ScanLevel* end() const { return levels_.data() + size_; }
    void clear() { size_ = 0; }
    void push_back(const ScanLevel& level) {
        PENUMBRA_ASSERT(size_ < kScanMaxLevels);
        if (size_ < kScanMaxLevels) levels_[size_++] = level;
    }

private:
    std::array<ScanLevel, kScanMaxLevels> levels_{};
    size_t size_ = 0;
};

/// The kernel of a dispatch (the PENUMBRA_SCAN_PASS define).
enum class ScanPass : uint32_t {
    Reduce = PENUMBRA_SCAN_PASS_REDUCE,
    Scan = PENUMBRA_SCAN_PASS_SCAN,
    Top = PENUMBRA_SCAN_PASS_TOP
};

inline const char* scanPassName(ScanPass pass) {
    return pass == ScanPass::Reduce ? "reduce" : pass == ScanPass::Scan ? "scan" : "top";
}

/// Which buffer a dispatch's binding views.
enum class ScanBuffer : uint32_t {
    None,       ///< nothing bound (the kernel does not touch that block in this dispatch)
    Input,      ///< the caller's input buffer
    Output,     ///< the caller's output buffer (== input buffer for an in-place scan)
    Scratch,    ///< the scratch buffer (plan.scratch_bytes)
    Constants   ///< the uniform buffer of all dispatches' PenumbraScanConstants
};

/// A byte range of one of the scan's buffers, bound as one block.
struct ScanBinding {
    ScanBuffer buffer = ScanBuffer::None;
    uint64_t offset = 0;  ///< absolute byte offset in that buffer (a multiple of plan.alignment / the uniform alignment)
    uint64_t size = 0;    ///< bytes
};

/// One compute dispatch of a plan.
struct ScanDispatch {
    ScanPass pass = ScanPass::Top;
    bool vec4 = false;              ///< uvec4 addressing (PENUMBRA_SCAN_VEC4 = 1): input/output also at the *_VEC4 bindings
    detail::DispatchGrid grid;      ///< grid.x * grid.y * 1 work groups
    uint32_t window = 0;            ///< which window / level of the plan it works on
    uint32_t level = 0;
    ScanBinding input;              ///< SSBO at PENUMBRA_SCAN_BINDING_INPUT (and _INPUT_VEC4 when vec4)
    ScanBinding output;             ///< SSBO at PENUMBRA_SCAN_BINDING_OUTPUT (and _OUTPUT_VEC4); None for reduce
    ScanBinding partials;           ///< SSBO at PENUMBRA_SCAN_BINDING_PARTIALS: the scratch, or None
    ScanBinding constants;          ///< UBO at PENUMBRA_SCAN_BINDING_CONSTANTS: this dispatch's block
};

/// Everything the GPU scan of n elements will do, computed without GL.
///
/// Windows: the first main_windows windows hold n - tail_elements elements in chunks of
/// window_elements (the last may be shorter); when n > 4 is not a multiple of 4, one more window
/// holds the last tail_elements (1 to 3) elements, so every main window's count is a multiple of 4
/// and the uvec4 kernels never meet a partial uvec4. Window w > 0 starts from the running total
/// window w - 1 left in carry word w % 2 (scratch word w % 2).
///
/// dispatch_list / constants: the dispatches in recording order for the kind and byte offsets
/// planScan was given (both empty for n == 0), constants[i] belonging to dispatch_list[i].
struct ScanPlan {
    uint64_t n = 0;
    ScanKind kind = ScanKind::Exclusive;
    uint64_t input_offset = 0;      ///< byte offsets of the ranges (multiples of 4)
    uint64_t output_offset = 0;
    uint32_t group_size = 0;        ///< resolved options
    uint32_t items_per_thread = 0;
    uint64_t top_elements = 0;      ///< group_size * items_per_thread: what the top pass scans at most
    uint32_t alignment = 0;         ///< lcm(16, binding_alignment): binding offsets, scratch arrays
    uint64_t window_elements = 0;   ///< elements per main window, a multiple of top_elements
    uint64_t main_windows = 0;      ///< ceil((n - tail_elements) / window_elements)
    uint64_t tail_elements = 0;     ///< 0, or n % 4 when n > 4 and n % 4 != 0
    uint64_t windows = 0;           ///< main_windows + (tail_elements != 0)
    ScanLevels levels;              ///< a full main window (the first); levels.back().top
    ScanLevels last_levels;         ///< the last main window (== levels when main_windows == 1)
    ScanLevels tail_levels;         ///< the tail window: one top level, or empty
    uint64_t scratch_bytes = 0;     ///< carry words (at 0, padded to alignment) + tile-sum arrays
    uint64_t dispatches = 0;        ///< compute dispatches in total (== dispatch_list.size())
    uint32_t constants_stride = 0;  ///< bytes between dispatches' constants: 32 rounded up to uniform_alignment
    uint64_t constants_bytes = 0;   ///< the uniform buffer: dispatches * constants_stride
    std::vector<ScanDispatch> dispatch_list;
    std::vector<shared::PenumbraScanConstants> constants;

    /// First element of window w.
    uint64_t windowFirst(uint64_t w) const { return w < main_windows ? w * window_elements : n - tail_elements; }
    /// The levels of window w.
    const ScanLevels& windowLevels(uint64_t w) const {
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
// The carry words fit the first 16 bytes of scratch (alignment is at least 16).
static_assert(PENUMBRA_SCAN_CARRY_WORDS * 4 <= 16);
// kScanMaxLevels: 2^32 elements, 4 per tile, top level >= 32 * 4: 2^32 / 4^13 <= 128.
static_assert(kScanMaxLevels >= 14);

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
/// Bytes between two dispatches' constants in the uniform buffer.
inline uint32_t scanConstantsStride(const ScanLimits& limits) {
    return static_cast<uint32_t>(alignUp(sizeof(shared::PenumbraScanConstants), limits.uniform_alignment));
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

/// foldDispatch without its checks, for plans whose limits were validated already (the
/// per-frame path must not throw). Same grid as foldDispatch.
inline DispatchGrid foldScanGrid(uint64_t groups, uint64_t max_x) {
    DispatchGrid grid;
    grid.groups = groups;
    if (groups == 0) return grid;
    const uint64_t y = divUp(groups, max_x);
    grid.x = static_cast<uint32_t>(divUp(groups, y));
    grid.y = static_cast<uint32_t>(y);
    return grid;
}

/// Levels of one window of `count` elements into `levels`; the first tile-sum array starts at
/// `offset` bytes; returns the end of the last one. Allocates and throws nothing.
inline uint64_t planScanLevels(uint64_t count, uint64_t items, uint64_t group_size, uint64_t alignment,
                               const ScanLimits& limits, uint64_t offset, ScanLevels& levels) {
    levels.clear();
    while (count > 0 && levels.size() < kScanMaxLevels) {
        ScanLevel level;
        level.count = count;
        level.tiles = divUp(count, items);
        level.top = count <= items * group_size;
        level.grid = foldScanGrid(level.top ? 1 : divUp(level.tiles, group_size), limits.max_groups_x);
        if (!level.top) {
            level.partials_offset = offset;
            offset += alignUp(level.tiles * 4, alignment);
        }
        levels.push_back(level);
        if (level.top) break;
        count = level.tiles;
    }
    return offset;
}

/// Checks options and limits once (throws penumbra::Error naming the bad value) and returns the
/// resolved options; what every later planScanShape / forEachScanDispatch call relies on.
inline ScanOptions validateScanSetup(const ScanOptions& options, const ScanLimits& limits) {
    PENUMBRA_CHECK(limits.binding_alignment > 0 && limits.binding_alignment % 4 == 0,
                   "penumbra: ScanLimits::binding_alignment ", limits.binding_alignment,
                   " is not a positive multiple of 4");
    PENUMBRA_CHECK(limits.uniform_alignment > 0, "penumbra: ScanLimits::uniform_alignment must be positive");
    PENUMBRA_CHECK(limits.max_groups_x > 0 && limits.max_groups_y > 0, "penumbra: dispatch limits must be positive");
    const ScanOptions resolved = resolveScanOptions(options, limits);
    const uint64_t top = uint64_t(resolved.group_size) * resolved.items_per_thread;
    const uint64_t slack = scanAlignment(limits) / 4 - 1;
    const uint64_t fit = limits.max_binding_bytes / 4 > slack ? limits.max_binding_bytes / 4 - slack : 0;
    PENUMBRA_CHECK(fit / top > 0, "penumbra: GL_MAX_SHADER_STORAGE_BLOCK_SIZE ", limits.max_binding_bytes,
                   " cannot hold one scan group's ", top, " elements");
    PENUMBRA_CHECK(resolved.window_elements == 0 || resolved.window_elements / top > 0,
                   "penumbra: ScanOptions::window_elements ", resolved.window_elements, " is smaller than one group's ",
                   top, " elements");
    return resolved;
}

/// The windows, levels and scratch of a scan of n <= kScanMaxElements elements with options
/// already resolved by validateScanSetup (no checks, no allocation, no exception). Leaves the
/// dispatch list and constants of `plan` untouched.
inline void planScanShape(uint64_t n, ScanKind kind, uint64_t input_offset, uint64_t output_offset,
                          const ScanOptions& resolved, const ScanLimits& limits, ScanPlan& plan) {
    plan.n = n;
    plan.kind = kind;
    plan.input_offset = input_offset;
    plan.output_offset = output_offset;
    plan.group_size = resolved.group_size;
    plan.items_per_thread = resolved.items_per_thread;
    plan.top_elements = uint64_t(resolved.group_size) * resolved.items_per_thread;
    plan.alignment = static_cast<uint32_t>(scanAlignment(limits));
    plan.constants_stride = scanConstantsStride(limits);
    // A window's binding starts up to alignment - 4 bytes before its first element.
    const uint64_t slack = plan.alignment / 4 - 1;
    const uint64_t fit = limits.max_binding_bytes / 4 > slack ? limits.max_binding_bytes / 4 - slack : 0;
    uint64_t window = fit / plan.top_elements * plan.top_elements;
    if (resolved.window_elements != 0) {
        window = std::min(window, resolved.window_elements / plan.top_elements * plan.top_elements);
    }
    plan.window_elements = window;
    plan.tail_elements = (n > 4 && n % 4 != 0) ? n % 4 : 0;
    const uint64_t main = n - plan.tail_elements;
    plan.main_windows = n == 0 ? 0 : divUp(main, window);
    plan.windows = plan.main_windows + (plan.tail_elements != 0);
    plan.levels.clear();
    plan.last_levels.clear();
    plan.tail_levels.clear();
    plan.scratch_bytes = 0;
    plan.dispatches = 0;
    plan.constants_bytes = 0;
    if (n == 0) return;
    const uint64_t items = plan.items_per_thread, group = plan.group_size;
    const uint64_t end =
        planScanLevels(std::min(main, window), items, group, plan.alignment, limits, plan.alignment, plan.levels);
    if (plan.main_windows == 1) {
        plan.last_levels = plan.levels;
    } else {
        planScanLevels(main - (plan.main_windows - 1) * window, items, group, plan.alignment, limits, plan.alignment,
                       plan.last_levels);
    }
    if (plan.tail_elements) {
        planScanLevels(plan.tail_elements, items, group, plan.alignment, limits, plan.alignment, plan.tail_levels);
    }
    // Scratch: the carry words (windows > 1) and the tile-sum arrays (levels > 1); the first
    // window is the largest, so its layout bounds every window's.
    plan.scratch_bytes = (plan.levels.size() > 1 || plan.windows > 1) ? end : 0;
    for (uint64_t w = 0; w < plan.windows; ++w) plan.dispatches += 2 * plan.windowLevels(w).size() - 1;
    plan.constants_bytes = plan.dispatches * plan.constants_stride;
}

/// Calls emit(const ScanDispatch&, const shared::PenumbraScanConstants&) for every dispatch of a
/// plan whose shape planScanShape filled, in recording order. Allocates and throws nothing: the
/// one definition of the dispatch list (planScan collects it, Scanner records it).
template <typename Emit>
void forEachScanDispatch(const ScanPlan& plan, Emit&& emit) {
    const uint64_t alignment = plan.alignment;
    auto shiftOf = [&](uint64_t offset) { return static_cast<uint32_t>(offset % alignment / 4); };
    // Both shifts are the same for every window (main windows start whole groups' worth of
    // elements apart, multiples of 16 bytes; the tail window has a count below 4 anyway).
    const bool user_quads = shiftOf(plan.input_offset) % 4 == 0 && shiftOf(plan.output_offset) % 4 == 0;
    const bool inclusive = plan.kind == ScanKind::Inclusive;
    const ScanBinding partials =
        plan.scratch_bytes ? ScanBinding{ScanBuffer::Scratch, 0, plan.scratch_bytes} : ScanBinding{};
    struct Data {
        ScanBuffer buffer;
        uint64_t offset;  // byte offset of element 0
    };
    // The bound range of `count` elements of `data`: from the aligned offset at or before it.
    auto bindingOf = [&](const Data& data, uint64_t count) {
        const uint64_t shift = shiftOf(data.offset);
        return ScanBinding{data.buffer, data.offset - shift * 4, (shift + count) * 4};
    };
    uint64_t index = 0;
    for (uint64_t w = 0; w < plan.windows; ++w) {
        const ScanLevels& levels = plan.windowLevels(w);
        const uint64_t first = plan.windowFirst(w);
        const Data in{ScanBuffer::Input, plan.input_offset + first * 4};
        const Data out{ScanBuffer::Output, plan.output_offset + first * 4};
        const size_t top = levels.size() - 1;
        // uvec4 addressing needs whole uvec4s: shifts and count multiples of 4 (the scratch
        // arrays start aligned, so only their counts matter).
        auto quads = [&](size_t l) { return (l == 0 ? user_quads : true) && levels[l].count % 4 == 0; };
        auto data = [&](size_t l) { return l == 0 ? in : Data{ScanBuffer::Scratch, levels[l - 1].partials_offset}; };
        auto one = [&](ScanPass pass, size_t l, const Data& src, const Data* dst, uint64_t partials_index,
                       uint32_t flags, uint32_t carry_in, uint32_t carry_out) {
            const ScanLevel& level = levels[l];
            ScanDispatch d;
            d.pass = pass;
            d.vec4 = quads(l);
            d.grid = level.grid;
            d.window = static_cast<uint32_t>(w);
            d.level = static_cast<uint32_t>(l);
            d.input = bindingOf(src, level.count);
            if (dst) d.output = bindingOf(*dst, level.count);
            d.partials = partials;
            d.constants = ScanBinding{ScanBuffer::Constants, index * plan.constants_stride,
                                      sizeof(shared::PenumbraScanConstants)};
            shared::PenumbraScanConstants c{};
            c.count = static_cast<uint32_t>(level.count);
            c.input_shift = shiftOf(src.offset);
            c.output_shift = dst ? shiftOf(dst->offset) : 0u;
            c.partials_index = static_cast<uint32_t>(partials_index);
            c.carry_in_index = carry_in;
            c.carry_out_index = carry_out;
            c.flags = flags;
            c.reserved = 0;
            emit(static_cast<const ScanDispatch&>(d), static_cast<const shared::PenumbraScanConstants&>(c));
            ++index;
        };
        // Up: every level below the top leaves one sum per tile for the level above.
        for (size_t l = 0; l < top; ++l) {
            one(ScanPass::Reduce, l, data(l), nullptr, levels[l].partials_offset / 4, 0, 0, 0);
        }
        // Top: one group, exclusive in place (or, with one level, straight to the output with
        // the caller's kind), taking the previous window's carry (word w % 2) and leaving the
        // next one's (word (w + 1) % 2): never the word it reads.
        uint32_t flags = 0;
        if (top == 0 && inclusive) flags |= PENUMBRA_SCAN_FLAG_INCLUSIVE;
        if (w > 0) flags |= PENUMBRA_SCAN_FLAG_READ_OFFSETS;
        if (w + 1 < plan.windows) flags |= PENUMBRA_SCAN_FLAG_WRITE_CARRY;
        const Data top_out = top == 0 ? out : data(top);
        one(ScanPass::Top, top, data(top), &top_out, 0, flags, static_cast<uint32_t>(w % 2),
            static_cast<uint32_t>((w + 1) % 2));
        // Down: each level adds its tiles' scanned offsets.
        for (size_t l = top; l-- > 0;) {
            const uint32_t down_flags = (l == 0 && inclusive) ? PENUMBRA_SCAN_FLAG_INCLUSIVE : 0;
            const Data dst = l == 0 ? out : data(l);
            one(ScanPass::Scan, l, data(l), &dst, levels[l].partials_offset / 4, down_flags, 0, 0);
        }
    }
}

/// Upper bounds over every n <= max_n (what Scanner::reserve sizes): scratch bytes (at least
/// the carry words) and dispatches. Scratch: the first window's levels of min(max_n, window)
/// elements plus the carry area (levels and arrays grow with the count); dispatches: every main
/// window at most 2 * levels - 1, plus one for a tail window.
struct ScanBounds {
    uint64_t scratch_bytes = 0;
    uint64_t dispatches = 0;
};
inline ScanBounds scanBounds(uint64_t max_n, const ScanOptions& resolved, const ScanLimits& limits) {
    ScanPlan shape;
    planScanShape(max_n, ScanKind::Exclusive, 0, 0, resolved, limits, shape);
    ScanBounds b;
    if (max_n == 0) return b;
    ScanLevels levels;
    b.scratch_bytes = planScanLevels(std::min(max_n, shape.window_elements), shape.items_per_thread,
                                     shape.group_size, shape.alignment, limits, shape.alignment, levels);
    b.dispatches = divUp(max_n, shape.window_elements) * (2 * levels.size() - 1) + 1;
    return b;
}

}  // namespace detail

/// Pure setup: what a scan of n elements of `kind`, reading the input at byte `input_offset` of
/// its buffer and writing the output at `output_offset` of its own, does under `options` and
/// `limits` (no GL): windows, levels, scratch, and the dispatch list with each dispatch's
/// constants. Throws penumbra::Error for n > kScanMaxElements, offsets that are not multiples of
/// 4, bad options, or limits too small for one group.
inline ScanPlan planScan(uint64_t n, const ScanOptions& options = {}, const ScanLimits& limits = {},
                         ScanKind kind = ScanKind::Exclusive, uint64_t input_offset = 0, uint64_t output_offset = 0) {
    PENUMBRA_CHECK(n <= kScanMaxElements, "penumbra: scan of n = ", n, " elements exceeds kScanMaxElements = ",
                   kScanMaxElements);
    PENUMBRA_CHECK(input_offset % 4 == 0 && output_offset % 4 == 0, "penumbra: scan offsets ", input_offset, " and ",
                   output_offset, " bytes must be multiples of 4");
    const ScanOptions resolved = detail::validateScanSetup(options, limits);
    ScanPlan plan;
    detail::planScanShape(n, kind, input_offset, output_offset, resolved, limits, plan);
    for (const ScanLevels* levels : {&plan.levels, &plan.last_levels, &plan.tail_levels}) {
        for (const ScanLevel& level : *levels) {
            // The checked fold: throws when even a 2D grid cannot hold the groups.
            detail::foldDispatch(level.grid.groups, limits.max_groups_x, limits.max_groups_y);
        }
    }
    PENUMBRA_CHECK(plan.scratch_bytes <= limits.max_binding_bytes, "penumbra: scan scratch of ", plan.scratch_bytes,
                   " bytes exceeds GL_MAX_SHADER_STORAGE_BLOCK_SIZE ", limits.max_binding_bytes);
    plan.dispatch_list.reserve(static_cast<size_t>(plan.dispatches));
    plan.constants.reserve(static_cast<size_t>(plan.dispatches));
    detail::forEachScanDispatch(plan, [&](const ScanDispatch& d, const shared::PenumbraScanConstants& c) {
        plan.dispatch_list.push_back(d);
        plan.constants.push_back(c);
    });
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

#endif
