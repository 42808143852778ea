// penumbra scan: the CPU twin against the standard library; the pure plan and its dispatch list
// (each dispatch's constants and bound ranges) without GL; an RHI-style replay of a plan with raw GL
// calls (no Scanner); the GPU scan against the CPU twin (sizes across work-group, block, level,
// dispatch-limit and binding-window edges; exclusive and inclusive; in place and out of place;
// nonzero and unaligned offsets; wrap-around; ballot/KHR vs portable); the Status of every per-frame
// misuse; the GL state contract (nothing reset, foreign bindings and queued GL errors survive);
// load-time validation errors; the workgroup-scan snippet through its hook, including a hook that
// disagrees with local_size_x failing to compile. Outputs are poisoned before each run and every
// element is checked; guard words around every range must survive. Seeds: support/test_support.hpp.
//
// PENUMBRA_ASSERT is redefined (before any penumbra header) to count instead of abort, so the
// misuse tests run in Debug builds too and can check that the assert fired.
namespace {
int g_scan_test_asserts = 0;
}
// The counting operator new/delete below are malloc/free pairs; GCC's inliner sees free() on a
// pointer from "new" and warns at every call site.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
#define PENUMBRA_ASSERT(cond) ((cond) ? void(0) : void(++g_scan_test_asserts))

#include "shader_catalog.hpp"
#include "support/gl_test_support.hpp"
#include "support/test_support.hpp"

#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/scan.hpp>
#include <penumbra/gl/shader.hpp>
#include <penumbra/scan.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <new>
#include <type_traits>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <map>
#include <numeric>
#include <random>
#include <string>
#include <vector>

using penumbra::test::firstMismatch;
using penumbra::test::contains;
using penumbra::test::context;
using penumbra::test::errorOf;
using penumbra::test::testSeed;

namespace {

std::vector<uint32_t> randomValues(std::mt19937& rng, size_t n) {
    std::vector<uint32_t> v(n);
    for (auto& x : v) x = rng();  // full 32-bit range: sums wrap mod 2^32 many times
    return v;
}

std::vector<uint32_t> cpuScan(const std::vector<uint32_t>& in, penumbra::ScanKind kind) {
    std::vector<uint32_t> out(in.size());
    penumbra::scanCpu(in.data(), out.data(), in.size(), kind);
    return out;
}


}  // namespace

// ---- CPU: the twin and the plan -----------------------------------------------------------------

TEST_CASE("scanCpu equals std::exclusive_scan / std::inclusive_scan, in place and out of place") {
    const uint32_t seed = testSeed();
    std::mt19937 rng(seed);
    for (size_t n : {size_t(0), size_t(1), size_t(2), size_t(3), size_t(255), size_t(256), size_t(257),
                     size_t(4097), size_t(65537), size_t(1000003)}) {
        CAPTURE(n);
        std::vector<uint32_t> in = randomValues(rng, n);
        std::vector<uint32_t> want_ex(n), want_in(n);
        std::exclusive_scan(in.begin(), in.end(), want_ex.begin(), uint32_t(0));
        std::inclusive_scan(in.begin(), in.end(), want_in.begin());
        std::vector<uint32_t> out(n, 0xdeadbeefu);
        penumbra::scanCpu(in.data(), out.data(), n, penumbra::ScanKind::Exclusive);
        CHECK(firstMismatch(out, want_ex) == "");
        std::fill(out.begin(), out.end(), 0xdeadbeefu);
        penumbra::scanCpu(in.data(), out.data(), n, penumbra::ScanKind::Inclusive);
        CHECK(firstMismatch(out, want_in) == "");
        std::vector<uint32_t> inplace = in;
        penumbra::scanCpu(inplace.data(), inplace.data(), n, penumbra::ScanKind::Exclusive);
        CHECK(firstMismatch(inplace, want_ex) == "");
        inplace = in;
        penumbra::scanCpu(inplace.data(), inplace.data(), n, penumbra::ScanKind::Inclusive);
        CHECK(firstMismatch(inplace, want_in) == "");
    }
    // Wrap-around: 0xFFFFFFFF = -1 mod 2^32.
    std::vector<uint32_t> ones(70000, 0xFFFFFFFFu), out(ones.size());
    penumbra::scanCpu(ones.data(), out.data(), ones.size(), penumbra::ScanKind::Exclusive);
    for (size_t i = 0; i < out.size(); ++i) {
        if (out[i] != static_cast<uint32_t>(0u - static_cast<uint32_t>(i))) FAIL("wrap-around at ", i);
    }
    penumbra::scanCpu(nullptr, nullptr, 0, penumbra::ScanKind::Inclusive);  // n == 0: no access
    std::vector<uint32_t> buf(16, 1u);
    CHECK(contains(errorOf([&] { penumbra::scanCpu(buf.data(), buf.data() + 1, 8, penumbra::ScanKind::Exclusive); }),
                   "offset 1 elements"));
    CHECK(contains(errorOf([&] { penumbra::scanCpu(nullptr, buf.data(), 3, penumbra::ScanKind::Exclusive); }),
                   "null input"));
}

namespace {

// The dispatch list of every plan: one constants block per dispatch at stride offsets, ranges
// inside the limits and aligned, the windows' carries in alternating words (never the word read).
void checkDispatchInvariants(const penumbra::ScanPlan& p, const penumbra::ScanLimits& limits) {
    using penumbra::ScanBuffer;
    REQUIRE(p.dispatch_list.size() == p.dispatches);
    REQUIRE(p.constants.size() == p.dispatches);
    CHECK(p.constants_stride % limits.uniform_alignment == 0);
    CHECK(p.constants_stride >= sizeof(penumbra::shared::PenumbraScanConstants));
    CHECK(p.constants_bytes == p.dispatches * p.constants_stride);
    uint64_t tops = 0;
    for (size_t i = 0; i < p.dispatch_list.size(); ++i) {
        CAPTURE(i);
        const penumbra::ScanDispatch& d = p.dispatch_list[i];
        const penumbra::shared::PenumbraScanConstants& c = p.constants[i];
        CHECK(d.constants.buffer == ScanBuffer::Constants);
        CHECK(d.constants.offset == i * p.constants_stride);
        CHECK(d.constants.size == 32);
        const penumbra::ScanLevel& level = p.windowLevels(d.window)[d.level];
        CHECK(c.count == level.count);
        CHECK(d.grid.groups == level.grid.groups);
        CHECK(d.input.offset % p.alignment == 0);
        CHECK(d.input.size == (c.input_shift + uint64_t(c.count)) * 4);
        CHECK(d.input.size <= limits.max_binding_bytes);
        CHECK(c.reserved == 0);
        if (d.vec4) {
            CHECK(c.count % 4 == 0);
            CHECK(c.input_shift % 4 == 0);
            CHECK(c.output_shift % 4 == 0);
        }
        if (d.pass == penumbra::ScanPass::Reduce) {
            CHECK(d.output.buffer == ScanBuffer::None);
        } else {
            CHECK(d.output.buffer != ScanBuffer::None);
            CHECK(d.output.offset % p.alignment == 0);
            CHECK(d.output.size == (c.output_shift + uint64_t(c.count)) * 4);
        }
        if (d.level == 0) {
            CHECK(d.input.buffer == ScanBuffer::Input);
            CHECK(d.input.offset + c.input_shift * 4 == p.input_offset + p.windowFirst(d.window) * 4);
            if (d.pass != penumbra::ScanPass::Reduce && (d.pass == penumbra::ScanPass::Scan || level.top)) {
                CHECK(d.output.buffer == ScanBuffer::Output);
                CHECK(d.output.offset + c.output_shift * 4 == p.output_offset + p.windowFirst(d.window) * 4);
            }
        } else {
            CHECK(d.input.buffer == ScanBuffer::Scratch);
            CHECK(c.input_shift == 0);
        }
        if (p.scratch_bytes) {
            CHECK(d.partials.buffer == ScanBuffer::Scratch);
            CHECK(d.partials.offset == 0);
            CHECK(d.partials.size == p.scratch_bytes);
        } else {
            CHECK(d.partials.buffer == ScanBuffer::None);
        }
        if (d.pass == penumbra::ScanPass::Top) {
            ++tops;
            CHECK(c.carry_in_index != c.carry_out_index);  // barrier() orders shared memory only
            CHECK(c.carry_in_index == d.window % 2);
            CHECK(c.carry_out_index == (d.window + 1) % 2);
            CHECK(((c.flags & PENUMBRA_SCAN_FLAG_READ_OFFSETS) != 0) == (d.window > 0));
            CHECK(((c.flags & PENUMBRA_SCAN_FLAG_WRITE_CARRY) != 0) == (d.window + 1 < p.windows));
        } else {
            CHECK((c.flags & (PENUMBRA_SCAN_FLAG_READ_OFFSETS | PENUMBRA_SCAN_FLAG_WRITE_CARRY)) == 0);
            CHECK(c.partials_index * 4 == level.partials_offset);
        }
        const bool final_output = d.level == 0 && d.pass != penumbra::ScanPass::Reduce;
        CHECK(((c.flags & PENUMBRA_SCAN_FLAG_INCLUSIVE) != 0) == (final_output && p.kind == penumbra::ScanKind::Inclusive));
    }
    CHECK(tops == p.windows);
}

// Every plan must satisfy these, whatever n, options and limits.
void checkPlanInvariants(const penumbra::ScanPlan& p, const penumbra::ScanLimits& limits) {
    CAPTURE(p.n);
    uint64_t covered = 0, dispatches = 0;
    for (uint64_t w = 0; w < p.windows; ++w) {
        CAPTURE(w);
        const penumbra::ScanLevels& levels = p.windowLevels(w);
        REQUIRE(!levels.empty());
        CHECK(p.windowFirst(w) == covered);
        covered += levels[0].count;
        if (w < p.main_windows) {
            CHECK(levels[0].count <= p.window_elements);
            CHECK((levels[0].count % 4 == 0 || p.n < 4));  // uvec4 kernels never see a partial uvec4
        }
        // The binding of a window fits GL_MAX_SHADER_STORAGE_BLOCK_SIZE whatever the offset.
        CHECK((levels[0].count + p.alignment / 4 - 1) * 4 <= limits.max_binding_bytes);
        uint64_t previous_end = p.alignment;  // the carry word comes first
        for (size_t l = 0; l < levels.size(); ++l) {
            CAPTURE(l);
            const penumbra::ScanLevel& level = levels[l];
            CHECK(level.tiles == penumbra::detail::divUp(level.count, p.items_per_thread));
            CHECK(level.top == (l + 1 == levels.size()));
            CHECK(level.grid.x <= limits.max_groups_x);
            CHECK(level.grid.y <= limits.max_groups_y);
            if (level.top) {
                CHECK(level.count <= p.top_elements);
                CHECK(level.grid.groups == 1);
            } else {
                CHECK(level.count > p.top_elements);
                CHECK(level.grid.groups == penumbra::detail::divUp(level.tiles, p.group_size));
                CHECK(uint64_t(level.grid.x) * level.grid.y >= level.grid.groups);
                CHECK(levels[l + 1].count == level.tiles);
                CHECK(level.partials_offset % p.alignment == 0);
                CHECK(level.partials_offset >= previous_end);
                previous_end = level.partials_offset + level.tiles * 4;
                CHECK(previous_end <= p.scratch_bytes);
            }
        }
        if (p.windows > 1) CHECK(p.scratch_bytes >= p.alignment);
        dispatches += 2 * levels.size() - 1;
    }
    CHECK(covered == p.n);
    CHECK(dispatches == p.dispatches);
    CHECK(p.scratch_bytes <= limits.max_binding_bytes);
    checkDispatchInvariants(p, limits);
}

}  // namespace

TEST_CASE("planScan: windows, levels, tiles, folded grids and scratch without GL") {
    using penumbra::planScan;
    penumbra::ScanLimits llvmpipe;  // the values Mesa llvmpipe reports
    llvmpipe.max_binding_bytes = 134217728;
    llvmpipe.binding_alignment = 16;

    const penumbra::ScanPlan defaults = planScan(0, {}, llvmpipe);
    CHECK(defaults.group_size == PENUMBRA_SCAN_DEFAULT_GROUP_SIZE);
    CHECK(defaults.items_per_thread == PENUMBRA_SCAN_DEFAULT_ITEMS_PER_THREAD);
    CHECK(defaults.windows == 0);
    CHECK(defaults.levels.empty());
    CHECK(defaults.scratch_bytes == 0);
    CHECK(defaults.dispatches == 0);

    // The numbers below use 256 invocations x 32 items (8192 elements per group).
    penumbra::ScanOptions o32;
    o32.group_size = 256;
    o32.items_per_thread = 32;
    CHECK(planScan(0, o32, llvmpipe).top_elements == 8192);

    // One group's worth: the top pass alone, no scratch.
    const penumbra::ScanPlan one = planScan(8192, o32, llvmpipe);
    CHECK(one.windows == 1);
    REQUIRE(one.levels.size() == 1);
    CHECK(one.levels[0].top);
    CHECK(one.levels[0].tiles == 256);
    CHECK(one.scratch_bytes == 0);
    CHECK(one.dispatches == 1);

    // Two levels: reduce (257 tile sums), top, scan.
    const penumbra::ScanPlan two = planScan(8196, o32, llvmpipe);
    CHECK(two.windows == 1);
    CHECK(two.tail_elements == 0);
    REQUIRE(two.levels.size() == 2);
    CHECK(two.levels[0].tiles == 257);
    CHECK(two.levels[0].grid.groups == 2);
    CHECK(two.levels[0].partials_offset == 16);  // after the carry word, 16-byte aligned
    CHECK(two.levels[1].count == 257);
    CHECK(two.levels[1].top);
    CHECK(two.scratch_bytes == 16 + 1040);
    CHECK(two.dispatches == 3);

    // A ragged tail (n % 4 != 0, n > 4) becomes its own single-group window after the carry.
    const penumbra::ScanPlan ragged = planScan(8193, o32, llvmpipe);
    CHECK(ragged.tail_elements == 1);
    CHECK(ragged.main_windows == 1);
    CHECK(ragged.windows == 2);
    REQUIRE(ragged.levels.size() == 1);
    CHECK(ragged.levels[0].count == 8192);
    REQUIRE(ragged.tail_levels.size() == 1);
    CHECK(ragged.tail_levels[0].count == 1);
    CHECK(ragged.windowFirst(1) == 8192);
    CHECK(&ragged.windowLevels(1) == &ragged.tail_levels);
    CHECK(ragged.scratch_bytes == 16);  // the carry word only
    CHECK(ragged.dispatches == 2);
    const penumbra::ScanPlan three = planScan(3, o32, llvmpipe);  // n < 4: one scalar window
    CHECK(three.tail_elements == 0);
    CHECK(three.windows == 1);
    CHECK(three.scratch_bytes == 0);

    // 2^24: tiles of 32 shrink it to 2^19, 2^14, 512 elements; 512 fits the top pass.
    const penumbra::ScanPlan p24 = planScan(uint64_t(1) << 24, o32, llvmpipe);
    CHECK(p24.windows == 1);
    REQUIRE(p24.levels.size() == 4);
    CHECK(p24.levels[0].grid.groups == 2048);
    CHECK(p24.levels[1].count == (1u << 19));
    CHECK(p24.levels[2].count == (1u << 14));
    CHECK(p24.levels[3].count == 512);
    CHECK(p24.scratch_bytes == 16 + (1u << 21) + (1u << 16) + 2048);
    CHECK(p24.dispatches == 7);

    // 2^28 needs windows: 128 MiB per binding holds 2^25 - 3 uints after the slack of a 16-byte
    // aligned start, rounded down to whole 8192-element groups' worth.
    const penumbra::ScanPlan p28 = planScan(uint64_t(1) << 28, o32, llvmpipe);
    CHECK(p28.window_elements == (uint64_t(1) << 25) - 8192);
    CHECK(p28.main_windows == 9);
    CHECK(p28.windows == 9);
    REQUIRE(p28.levels.size() == 4);
    CHECK(p28.levels[0].grid.groups == 4095);
    CHECK(p28.last_levels[0].count == 65536);
    CHECK(p28.last_levels.size() == 2);
    CHECK(p28.scratch_bytes == 16 + 4193280 + 131040 + 4096);
    CHECK(p28.dispatches == 8 * 7 + 3);

    // Past the 65 535-group limit: 32 x 4 = 128-element groups, 65 537 groups fold into 2 rows.
    penumbra::ScanOptions small;
    small.group_size = 32;
    small.items_per_thread = 4;
    const uint64_t n_fold = 65536ull * 128 + 4;
    const penumbra::ScanPlan fold = planScan(n_fold, small, llvmpipe);
    CHECK(fold.tail_elements == 0);
    CHECK(fold.levels[0].grid.groups == 65537);
    CHECK(fold.levels[0].grid.y == 2);
    CHECK(fold.levels.size() == 10);

    // A 256-byte binding alignment (the GL maximum, the default limits) spaces the arrays.
    const penumbra::ScanPlan wide = planScan(n_fold, small);
    CHECK(wide.alignment == 256);
    CHECK(wide.levels[0].partials_offset == 256);
    CHECK(wide.levels[1].partials_offset == 256 + penumbra::detail::alignUp(2097153 * 4, 256));
    CHECK(wide.window_elements == ((uint64_t(1) << 25) - 63) / 128 * 128);

    // Explicit windows: whole groups' worth, carry word even with one level per window.
    penumbra::ScanOptions windowed = small;
    windowed.window_elements = 3 * 128 + 5;  // rounds down to 384
    const penumbra::ScanPlan win = planScan(1000, windowed, llvmpipe);
    CHECK(win.window_elements == 384);
    CHECK(win.windows == 3);
    CHECK(win.levels.size() == 2);
    CHECK(win.last_levels[0].count == 232);
    CHECK(win.windowFirst(2) == 768);
    CHECK(win.dispatches == 9);
    windowed.window_elements = 128;
    const penumbra::ScanPlan win1 = planScan(300, windowed, llvmpipe);
    CHECK(win1.windows == 3);
    CHECK(win1.levels.size() == 1);
    CHECK(win1.last_levels[0].count == 44);
    CHECK(win1.scratch_bytes == 16);
    CHECK(win1.dispatches == 3);

    // The invariants over a sweep of sizes, options and limits.
    penumbra::ScanLimits odd_limits;
    odd_limits.max_binding_bytes = 1 << 20;
    odd_limits.binding_alignment = 64;
    odd_limits.max_groups_x = 1000;
    const penumbra::ScanLimits all_limits[] = {llvmpipe, penumbra::ScanLimits{}, odd_limits};
    penumbra::ScanOptions big;
    big.group_size = 1024;
    big.items_per_thread = 64;
    const penumbra::ScanOptions all_options[] = {penumbra::ScanOptions{}, small, big, windowed};
    for (const auto& limits : all_limits) {
        for (const auto& options : all_options) {
            for (uint64_t n : {uint64_t(1), uint64_t(5), uint64_t(127), uint64_t(4097), uint64_t(65537), uint64_t(1000003),
                               (uint64_t(1) << 26) + 5, uint64_t(1) << 28, penumbra::kScanMaxElements}) {
                // Thousands of tiny windows add nothing but run time.
                if ((options.window_elements || limits.max_binding_bytes < (1u << 27)) && n > (1u << 26)) continue;
                checkPlanInvariants(planScan(n, options, limits), limits);
                checkPlanInvariants(planScan(n, options, limits, penumbra::ScanKind::Inclusive, 4, 40), limits);
            }
        }
    }

    // Errors name the value.
    CHECK(contains(errorOf([&] { planScan(penumbra::kScanMaxElements + 1, {}, llvmpipe); }), "4294967296"));
    penumbra::ScanOptions bad;
    bad.group_size = 48;
    CHECK(contains(errorOf([&] { planScan(10, bad); }), "group_size 48"));
    bad.group_size = 2048;
    CHECK(contains(errorOf([&] { planScan(10, bad); }), "group_size 2048"));
    bad.group_size = 16;
    CHECK(contains(errorOf([&] { planScan(10, bad); }), "group_size 16"));
    bad = {};
    bad.items_per_thread = 6;
    CHECK(contains(errorOf([&] { planScan(10, bad); }), "items_per_thread 6"));
    bad.items_per_thread = 68;
    CHECK(contains(errorOf([&] { planScan(10, bad); }), "items_per_thread 68"));
    bad = {};
    bad.window_elements = 100;
    CHECK(contains(errorOf([&] { planScan(10, bad); }), "window_elements 100"));
    penumbra::ScanLimits tiny;
    tiny.max_binding_bytes = 1024;
    CHECK(contains(errorOf([&] { planScan(10, {}, tiny); }), "GL_MAX_SHADER_STORAGE_BLOCK_SIZE 1024"));
    penumbra::ScanLimits small_groups;
    small_groups.max_group_size = 128;
    CHECK(contains(errorOf([&] { planScan(10, {}, small_groups); }), "[32, 128]"));
}

TEST_CASE("plan: the dispatch list and the constants each dispatch gets, without GL") {
    using penumbra::planScan;
    using penumbra::ScanBuffer;
    using penumbra::ScanPass;
    penumbra::ScanLimits llvmpipe;
    llvmpipe.max_binding_bytes = 134217728;
    llvmpipe.binding_alignment = 16;
    llvmpipe.uniform_alignment = 16;
    penumbra::ScanOptions o32;
    o32.group_size = 256;
    o32.items_per_thread = 32;

    // n == 0: nothing to record.
    CHECK(planScan(0, o32, llvmpipe).dispatch_list.empty());

    // Two levels, exclusive, aligned: reduce (uvec4), top over the 257 tile sums (scalar: 257 is
    // not a multiple of 4), scan (uvec4).
    const penumbra::ScanPlan two = planScan(8196, o32, llvmpipe);
    CHECK(two.constants_stride == 32);  // 32 bytes rounded up to a 16-byte alignment
    CHECK(two.constants_bytes == 96);
    REQUIRE(two.dispatch_list.size() == 3);
    const auto& reduce = two.dispatch_list[0];
    CHECK(reduce.pass == ScanPass::Reduce);
    CHECK(reduce.vec4);
    CHECK(reduce.grid.x == 2);
    CHECK(reduce.input.buffer == ScanBuffer::Input);
    CHECK(reduce.input.offset == 0);
    CHECK(reduce.input.size == 8196 * 4);
    CHECK(reduce.output.buffer == ScanBuffer::None);
    CHECK(reduce.partials.buffer == ScanBuffer::Scratch);
    CHECK(reduce.partials.size == two.scratch_bytes);
    CHECK(reduce.constants.offset == 0);
    CHECK(two.constants[0].count == 8196);
    CHECK(two.constants[0].partials_index == 4);  // tile sums after the 16-byte carry area
    CHECK(two.constants[0].flags == 0);
    const auto& top = two.dispatch_list[1];
    CHECK(top.pass == ScanPass::Top);
    CHECK_FALSE(top.vec4);
    CHECK(top.grid.x == 1);
    CHECK(top.input.buffer == ScanBuffer::Scratch);
    CHECK(top.input.offset == 16);
    CHECK(top.input.size == 257 * 4);
    CHECK(top.output.buffer == ScanBuffer::Scratch);  // in place on the tile sums
    CHECK(top.output.offset == 16);
    CHECK(top.constants.offset == 32);
    CHECK(two.constants[1].count == 257);
    CHECK(two.constants[1].flags == 0);  // exclusive in place, one window: no carry
    const auto& down = two.dispatch_list[2];
    CHECK(down.pass == ScanPass::Scan);
    CHECK(down.vec4);
    CHECK(down.input.buffer == ScanBuffer::Input);
    CHECK(down.output.buffer == ScanBuffer::Output);
    CHECK(down.output.size == 8196 * 4);
    CHECK(two.constants[2].partials_index == 4);
    CHECK(two.constants[2].flags == 0);
    CHECK(planScan(8196, o32, llvmpipe, penumbra::ScanKind::Inclusive).constants[2].flags ==
          PENUMBRA_SCAN_FLAG_INCLUSIVE);

    // Unaligned offsets: the ranges start at the aligned offset before the data, the shifts skip
    // the slack, and level 0 uses the scalar kernels.
    const penumbra::ScanPlan shifted = planScan(8196, o32, llvmpipe, penumbra::ScanKind::Inclusive, 4, 40);
    REQUIRE(shifted.dispatch_list.size() == 3);
    CHECK_FALSE(shifted.dispatch_list[0].vec4);
    CHECK(shifted.dispatch_list[0].input.offset == 0);
    CHECK(shifted.dispatch_list[0].input.size == (1 + 8196) * 4);
    CHECK(shifted.constants[0].input_shift == 1);
    CHECK(shifted.dispatch_list[2].output.offset == 32);
    CHECK(shifted.dispatch_list[2].output.size == (2 + 8196) * 4);
    CHECK(shifted.constants[2].input_shift == 1);
    CHECK(shifted.constants[2].output_shift == 2);
    CHECK(shifted.constants[2].flags == PENUMBRA_SCAN_FLAG_INCLUSIVE);
    // 16-byte multiples keep the uvec4 kernels.
    CHECK(planScan(8196, o32, llvmpipe, penumbra::ScanKind::Exclusive, 48, 16).dispatch_list[0].vec4);

    // One level per window, three windows: the carry alternates between words 0 and 1.
    penumbra::ScanOptions windowed;
    windowed.group_size = 32;
    windowed.items_per_thread = 4;
    windowed.window_elements = 128;
    const penumbra::ScanPlan win = planScan(300, windowed, llvmpipe, penumbra::ScanKind::Inclusive, 8, 8);
    REQUIRE(win.dispatch_list.size() == 3);
    for (size_t w = 0; w < 3; ++w) {
        CAPTURE(w);
        CHECK(win.dispatch_list[w].pass == ScanPass::Top);
        CHECK(win.dispatch_list[w].window == w);
        CHECK(win.dispatch_list[w].input.offset == w * 512);  // 8 + 128 w * 4 rounded down to 16
        CHECK(win.constants[w].input_shift == 2);
        CHECK(win.constants[w].count == (w < 2 ? 128u : 44u));
    }
    CHECK(win.constants[0].flags == (PENUMBRA_SCAN_FLAG_INCLUSIVE | PENUMBRA_SCAN_FLAG_WRITE_CARRY));
    CHECK(win.constants[0].carry_out_index == 1);
    CHECK(win.constants[1].flags ==
          (PENUMBRA_SCAN_FLAG_INCLUSIVE | PENUMBRA_SCAN_FLAG_READ_OFFSETS | PENUMBRA_SCAN_FLAG_WRITE_CARRY));
    CHECK(win.constants[1].carry_in_index == 1);
    CHECK(win.constants[1].carry_out_index == 0);
    CHECK(win.constants[2].flags == (PENUMBRA_SCAN_FLAG_INCLUSIVE | PENUMBRA_SCAN_FLAG_READ_OFFSETS));
    CHECK(win.constants[2].carry_in_index == 0);
    CHECK(win.dispatch_list[0].partials.buffer == ScanBuffer::Scratch);  // the carry words
    CHECK(win.dispatch_list[2].constants.offset == 64);

    // The default limits' 256-byte uniform alignment spaces the constants 256 bytes apart.
    const penumbra::ScanPlan wide = planScan(8196, o32);
    CHECK(wide.constants_stride == 256);
    CHECK(wide.dispatch_list[2].constants.offset == 512);

    // Odd offsets are refused.
    CHECK(contains(errorOf([&] { planScan(10, {}, {}, penumbra::ScanKind::Exclusive, 2, 0); }), "multiples of 4"));

    // reserve()'s bounds hold for every smaller n (the dispatch count is not monotonic in n: a
    // ragged tail adds a window).
    for (const penumbra::ScanOptions& options : {windowed, o32}) {
        const penumbra::ScanOptions resolved = penumbra::detail::validateScanSetup(options, llvmpipe);
        for (uint64_t max_n : {uint64_t(5), uint64_t(128), uint64_t(129), uint64_t(1000), uint64_t(8192),
                               uint64_t(8193), uint64_t(20000)}) {
            const penumbra::detail::ScanBounds bounds = penumbra::detail::scanBounds(max_n, resolved, llvmpipe);
            for (uint64_t n = 1; n <= max_n; n += (n < 300 ? 1 : 37)) {
                const penumbra::ScanPlan p = planScan(n, options, llvmpipe);
                if (p.dispatches > bounds.dispatches || p.scratch_bytes > bounds.scratch_bytes) {
                    FAIL("bounds of max_n = ", max_n, " miss n = ", n);
                }
            }
        }
    }
}

// ---- GPU ------------------------------------------------------------------------------------------

namespace {

penumbra::Scanner& defaultScanner() {
    context();
    static penumbra::Scanner scanner;
    return scanner;
}

constexpr uint32_t kPoison = 0xdeadbeefu;
constexpr uint32_t kGuard = 0x5ca1ab1eu;
constexpr size_t kGuardWords = 16;

penumbra::BufferRange rangeOf(const penumbra::gl::Buffer& buffer, uint64_t offset, uint64_t n) {
    return {buffer.id(), offset, n * 4};
}

// One GPU run through the per-frame API: input placed at in_offset (bytes) of its buffer, output
// at out_offset of another buffer (or of the same buffer when in_place), guard words everywhere
// else; reserve + validate at "load time", then scan() must return Ok; checks every output
// element against the CPU twin and that every guard word survived.
void checkGpuScan(penumbra::Scanner& scanner, const std::vector<uint32_t>& values, penumbra::ScanKind kind,
                  bool in_place, size_t in_offset, size_t out_offset) {
    const size_t n = values.size();
    CAPTURE(n);
    CAPTURE(penumbra::scanKindName(kind));
    CAPTURE(in_place);
    CAPTURE(in_offset);
    CAPTURE(out_offset);
    if (in_place) out_offset = in_offset;
    const size_t in_words = in_offset / 4 + n + kGuardWords;
    std::vector<uint32_t> in_image(in_words, kGuard);
    std::copy(values.begin(), values.end(), in_image.begin() + static_cast<ptrdiff_t>(in_offset / 4));
    penumbra::gl::Buffer in_buffer = penumbra::gl::Buffer::fromVector(in_image);
    penumbra::gl::Buffer out_buffer;
    if (!in_place) {
        out_buffer = penumbra::gl::Buffer((out_offset / 4 + n + kGuardWords) * 4);
        out_buffer.fill(kGuard);
        // Poison the output range.
        std::vector<uint32_t> poison(n, kPoison);
        if (n) out_buffer.upload(out_offset, poison.data(), n * 4);
    }
    const penumbra::gl::Buffer& result_buffer = in_place ? in_buffer : out_buffer;
    const penumbra::BufferRange input = rangeOf(in_buffer, in_offset, n);
    const penumbra::BufferRange output = rangeOf(result_buffer, out_offset, n);
    scanner.reserve(n);
    scanner.validate(input, output, n);
    CHECK(scanner.scan(kind, input, output, n) == penumbra::Status::Ok);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);  // the caller's half of the contract
    penumbra::gl::checkErrors("scan");

    const std::vector<uint32_t> want = cpuScan(values, kind);
    std::vector<uint32_t> image = result_buffer.download<uint32_t>();
    std::vector<uint32_t> got(image.begin() + static_cast<ptrdiff_t>(out_offset / 4),
                              image.begin() + static_cast<ptrdiff_t>(out_offset / 4 + n));
    CHECK(firstMismatch(got, want) == "");
    // Guards around the output range (and, out of place, the untouched input).
    size_t bad_guards = 0;
    for (size_t i = 0; i < out_offset / 4; ++i) bad_guards += image[i] != kGuard;
    for (size_t i = out_offset / 4 + n; i < image.size(); ++i) bad_guards += image[i] != kGuard;
    CHECK(bad_guards == 0);
    if (!in_place) {
        std::vector<uint32_t> in_after = in_buffer.download<uint32_t>();
        CHECK(firstMismatch(in_after, in_image) == "");
    }
}

// An engine with its own RHI: records a plan's dispatches with raw GL calls and its own programs,
// buffers and bindings — no Scanner involved. Returns the output range's contents.
std::vector<uint32_t> replayPlan(const penumbra::ScanPlan& plan, const std::vector<uint32_t>& values,
                                 uint64_t in_offset, uint64_t out_offset, bool in_place) {
    using penumbra::ScanBuffer;
    const uint64_t n = plan.n;
    std::map<std::pair<int, int>, penumbra::gl::Program> programs;  // (pass, vec4) -> program
    for (const penumbra::ScanDispatch& d : plan.dispatch_list) {
        auto key = std::make_pair(static_cast<int>(d.pass), d.vec4 ? 1 : 0);
        if (programs.count(key)) continue;
        const char* pass = d.pass == penumbra::ScanPass::Reduce ? "PENUMBRA_SCAN_PASS_REDUCE"
                           : d.pass == penumbra::ScanPass::Scan ? "PENUMBRA_SCAN_PASS_SCAN"
                                                                : "PENUMBRA_SCAN_PASS_TOP";
        programs[key] = penumbra::gl::buildComputeProgram(
            "penumbra/scan/scan.comp.glsl", {{"PENUMBRA_SCAN_PASS", pass},
                                             {"PENUMBRA_SCAN_GROUP_SIZE", std::to_string(plan.group_size)},
                                             {"PENUMBRA_SCAN_ITEMS_PER_THREAD", std::to_string(plan.items_per_thread)},
                                             {"PENUMBRA_SCAN_VEC4", d.vec4 ? "1" : "0"}});
    }
    std::vector<uint32_t> in_image(in_offset / 4 + n, kGuard);
    std::copy(values.begin(), values.end(), in_image.begin() + static_cast<ptrdiff_t>(in_offset / 4));
    penumbra::gl::Buffer input = penumbra::gl::Buffer::fromVector(in_image);
    penumbra::gl::Buffer output_storage(in_place ? 0 : (out_offset / 4 + n) * 4);
    output_storage.fill(kPoison);
    const GLuint output = in_place ? input.id() : output_storage.id();
    penumbra::gl::Buffer scratch(std::max<uint64_t>(plan.scratch_bytes, 16));
    scratch.fill(kPoison);  // scratch needs no initialisation
    // The constants: one block per dispatch at its offset, one upload.
    std::vector<unsigned char> constants(plan.constants_bytes);
    for (size_t i = 0; i < plan.dispatch_list.size(); ++i) {
        std::memcpy(constants.data() + plan.dispatch_list[i].constants.offset, &plan.constants[i],
                    sizeof(penumbra::shared::PenumbraScanConstants));
    }
    penumbra::gl::Buffer ubo(constants.size(), constants.data());
    auto name = [&](ScanBuffer b) -> GLuint {
        switch (b) {
            case ScanBuffer::Input: return input.id();
            case ScanBuffer::Output: return output;
            case ScanBuffer::Scratch: return scratch.id();
            case ScanBuffer::Constants: return ubo.id();
            default: return 0;
        }
    };
    auto bind = [&](GLenum target, GLuint index, const penumbra::ScanBinding& b) {
        if (b.buffer == ScanBuffer::None) return;
        glBindBufferRange(target, index, name(b.buffer), static_cast<GLintptr>(b.offset),
                          static_cast<GLsizeiptr>(b.size));
    };
    for (const penumbra::ScanDispatch& d : plan.dispatch_list) {
        bind(GL_SHADER_STORAGE_BUFFER, PENUMBRA_SCAN_BINDING_INPUT, d.input);
        bind(GL_SHADER_STORAGE_BUFFER, PENUMBRA_SCAN_BINDING_OUTPUT, d.output);
        if (d.vec4) {
            bind(GL_SHADER_STORAGE_BUFFER, PENUMBRA_SCAN_BINDING_INPUT_VEC4, d.input);
            bind(GL_SHADER_STORAGE_BUFFER, PENUMBRA_SCAN_BINDING_OUTPUT_VEC4, d.output);
        }
        bind(GL_SHADER_STORAGE_BUFFER, PENUMBRA_SCAN_BINDING_PARTIALS, d.partials);
        bind(GL_UNIFORM_BUFFER, PENUMBRA_SCAN_BINDING_CONSTANTS, d.constants);
        glUseProgram(programs[{static_cast<int>(d.pass), d.vec4 ? 1 : 0}].id());
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        glDispatchCompute(d.grid.x, d.grid.y, 1);
    }
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    penumbra::gl::checkErrors("plan replay");
    std::vector<uint32_t> got(n);
    if (n) {
        glGetNamedBufferSubData(output, static_cast<GLintptr>(out_offset), static_cast<GLsizeiptr>(n * 4), got.data());
    }
    glUseProgram(0);
    return got;
}

}  // namespace

TEST_CASE("RHI-style replay: a plan recorded with raw GL calls, no Scanner, equals scanCpu") {
    context();
    const penumbra::ScanLimits limits = penumbra::queryScanLimits();
    const uint32_t seed = testSeed(1);
    std::mt19937 rng(seed);
    penumbra::ScanOptions small;
    small.group_size = 32;
    small.items_per_thread = 4;
    penumbra::ScanOptions windowed = small;
    windowed.window_elements = 3 * 128;
    struct Case {
        penumbra::ScanOptions options;
        uint64_t n, in_offset, out_offset;
        penumbra::ScanKind kind;
        bool in_place;
    };
    const Case cases[] = {{{}, 1, 0, 0, penumbra::ScanKind::Exclusive, false},
                          {{}, 4097, 16, 48, penumbra::ScanKind::Inclusive, false},
                          {{}, 65537, 4, 40, penumbra::ScanKind::Exclusive, false},
                          {{}, (1u << 20) + 3, 12, 12, penumbra::ScanKind::Inclusive, true},
                          {small, 100003, 8, 0, penumbra::ScanKind::Exclusive, false},
                          {windowed, 10 * 384 + 77, 4, 8, penumbra::ScanKind::Inclusive, false},
                          {windowed, 5000, 16, 16, penumbra::ScanKind::Exclusive, true}};
    for (const Case& c : cases) {
        CAPTURE(c.n);
        CAPTURE(c.in_offset);
        CAPTURE(c.out_offset);
        CAPTURE(c.in_place);
        const penumbra::ScanPlan plan = penumbra::planScan(c.n, c.options, limits, c.kind, c.in_offset, c.out_offset);
        MESSAGE("n = ", c.n, ": ", plan.windows, " windows, ", plan.dispatches, " dispatches");
        const std::vector<uint32_t> values = randomValues(rng, c.n);
        CHECK(firstMismatch(replayPlan(plan, values, c.in_offset, c.out_offset, c.in_place), cpuScan(values, c.kind)) ==
              "");
    }
}

TEST_CASE("GPU scan equals the CPU twin across sizes, kinds, placements and offsets") {
    penumbra::Scanner& scanner = defaultScanner();
    const uint32_t seed = testSeed();
    MESSAGE("on ", context().renderer(), " (", context().platform(), "), workgroup scans on ",
            std::string(penumbra::scanSubgroupsName(scanner.subgroupMode())));
    std::mt19937 rng(seed);
    const uint64_t sizes[] = {0, 1, 2, 255, 256, 257, 4095, 4096, 4097, 65537, (1u << 20) + 3, (1u << 24) + 1};
    for (uint64_t n : sizes) {
        const std::vector<uint32_t> values = randomValues(rng, n);
        // Offsets cover both addressing modes: 16-byte multiples use the uvec4 kernels, other
        // multiples of 4 the scalar ones (and bind at an aligned offset with an element shift).
        checkGpuScan(scanner, values, penumbra::ScanKind::Exclusive, false, 16, 48);
        checkGpuScan(scanner, values, penumbra::ScanKind::Inclusive, false, 4, 40);
        checkGpuScan(scanner, values, penumbra::ScanKind::Exclusive, true, 12, 0);
        checkGpuScan(scanner, values, penumbra::ScanKind::Inclusive, true, 64, 0);
    }
}

TEST_CASE("GPU scan wraps around mod 2^32 like the CPU twin") {
    penumbra::Scanner& scanner = defaultScanner();
    const uint32_t seed = testSeed();
    std::mt19937 rng(seed);
    std::vector<uint32_t> big(100003);
    for (auto& x : big) x = 0xF0000000u | (rng() & 0x0FFFFFFFu);  // every partial sum wraps
    checkGpuScan(scanner, big, penumbra::ScanKind::Exclusive, false, 0, 0);
    checkGpuScan(scanner, big, penumbra::ScanKind::Inclusive, true, 8, 0);
    std::vector<uint32_t> ones(70001, 0xFFFFFFFFu);
    checkGpuScan(scanner, ones, penumbra::ScanKind::Exclusive, false, 20, 4);
}

TEST_CASE("GPU scan past the 65 535-group dispatch limit (2D-folded grids, many levels)") {
    context();
    penumbra::ScanOptions options;
    options.group_size = 32;
    options.items_per_thread = 4;
    penumbra::Scanner scanner(options);
    const uint64_t n = 65536ull * 128 + 1;
    const penumbra::ScanPlan plan = scanner.plan(n);
    CHECK(plan.levels[0].grid.groups > 65535);
    // GL's minimum GL_MAX_COMPUTE_WORK_GROUP_COUNT is 65 535 (llvmpipe's); NVIDIA reports 2^31 - 1
    // in x, so there the plan needs no fold (planScan's folding itself is tested on the CPU).
    if (scanner.limits().max_groups_x < plan.levels[0].grid.groups) {
        CHECK(plan.levels[0].grid.y > 1);
    } else {
        MESSAGE("the driver dispatches ", scanner.limits().max_groups_x, " groups in x: no 2D fold needed");
        CHECK(plan.levels[0].grid.y == 1);
    }
    const uint32_t seed = testSeed();
    MESSAGE(plan.levels[0].grid.groups, " groups as ", plan.levels[0].grid.x, " x ",
            plan.levels[0].grid.y, ", ", plan.levels.size(), " levels");
    std::mt19937 rng(seed);
    const std::vector<uint32_t> values = randomValues(rng, n);
    checkGpuScan(scanner, values, penumbra::ScanKind::Exclusive, false, 32, 4);
    checkGpuScan(scanner, values, penumbra::ScanKind::Inclusive, true, 16, 0);
}

TEST_CASE("GPU scan carries the running total across binding windows") {
    context();
    const uint32_t seed = testSeed();
    std::mt19937 rng(seed);
    SUBCASE("small explicit windows, one and two levels per window") {
        penumbra::ScanOptions options;
        options.group_size = 32;
        options.items_per_thread = 4;
        for (uint64_t window : {uint64_t(128), uint64_t(3 * 128)}) {
            options.window_elements = window;
            penumbra::Scanner scanner(options);
            for (uint64_t n : {uint64_t(127), uint64_t(128), uint64_t(129), uint64_t(10 * 384 + 77)}) {
                CAPTURE(window);
                const std::vector<uint32_t> values = randomValues(rng, n);
                checkGpuScan(scanner, values, penumbra::ScanKind::Exclusive, false, 4, 8);
                checkGpuScan(scanner, values, penumbra::ScanKind::Inclusive, true, 16, 0);
            }
        }
    }
    SUBCASE("several levels per window") {
        penumbra::ScanOptions options;
        options.group_size = 32;
        options.items_per_thread = 4;
        options.window_elements = 128 * 130;  // 4160 tiles: their sums need more levels
        penumbra::Scanner scanner(options);
        const uint64_t n = 5 * 128 * 130 / 2 + 3;
        CHECK(scanner.plan(n).levels.size() == 5);
        CHECK(scanner.plan(n).main_windows == 3);
        CHECK(scanner.plan(n).tail_elements == 3);
        const std::vector<uint32_t> values = randomValues(rng, n);
        checkGpuScan(scanner, values, penumbra::ScanKind::Inclusive, false, 12, 16);
        checkGpuScan(scanner, values, penumbra::ScanKind::Exclusive, true, 32, 0);
    }
    SUBCASE("the driver's GL_MAX_SHADER_STORAGE_BLOCK_SIZE") {
        penumbra::Scanner& scanner = defaultScanner();
        const uint64_t window = scanner.plan(1).window_elements;
        const uint64_t n = window + 4099;
        const penumbra::ScanPlan plan = scanner.plan(n);
        MESSAGE("GL_MAX_SHADER_STORAGE_BLOCK_SIZE ", scanner.limits().max_binding_bytes, " bytes: windows of ", window,
                " elements; n = ", n, " runs in ", plan.windows, " windows");
        CHECK(plan.main_windows == 2);
        CHECK((window + 3) * 4 <= scanner.limits().max_binding_bytes);
        const std::vector<uint32_t> values = randomValues(rng, n);
        checkGpuScan(scanner, values, penumbra::ScanKind::Exclusive, false, 4, 0);
    }
}

TEST_CASE("subgroup path against the forced portable path") {
    context();
    penumbra::ScanOptions portable_options;
    portable_options.allow_subgroups = false;
    penumbra::Scanner portable(portable_options);
    CHECK_FALSE(portable.usesSubgroups());
    CHECK(portable.subgroupMode() == penumbra::ScanSubgroups::None);
    penumbra::Scanner& preferred = defaultScanner();
    const uint32_t khr = penumbra::detail::computeSubgroupSize();
    const penumbra::ScanSubgroups expected =
        khr != 0 && preferred.options().group_size % khr == 0 ? penumbra::ScanSubgroups::Khr
        : penumbra::detail::glHasExtension("GL_ARB_shader_ballot") ? penumbra::ScanSubgroups::Ballot
                                                                    : penumbra::ScanSubgroups::None;
    MESSAGE(context().renderer(), ": default scanner uses ", std::string(penumbra::scanSubgroupsName(preferred.subgroupMode())),
            " (KHR subgroup size ", khr, ")");
    CHECK(preferred.subgroupMode() == expected);  // the construction self-check must pass too
    CHECK(preferred.usesSubgroups() == (expected != penumbra::ScanSubgroups::None));
    const uint32_t seed = testSeed();
    std::mt19937 rng(seed);
    for (uint64_t n : {uint64_t(1), uint64_t(300), uint64_t(8193), uint64_t(1000001)}) {
        const std::vector<uint32_t> values = randomValues(rng, n);
        checkGpuScan(preferred, values, penumbra::ScanKind::Exclusive, false, 0, 16);
        checkGpuScan(portable, values, penumbra::ScanKind::Exclusive, false, 0, 16);
        checkGpuScan(preferred, values, penumbra::ScanKind::Inclusive, true, 4, 0);
        checkGpuScan(portable, values, penumbra::ScanKind::Inclusive, true, 4, 0);
    }
}

TEST_CASE("other group sizes and items per thread") {
    context();
    const uint32_t seed = testSeed();
    std::mt19937 rng(seed);
    const std::pair<uint32_t, uint32_t> configs[] = {{32, 4}, {64, 8}, {128, 16}, {512, 4}, {1024, 64}};
    for (bool subgroups : {true, false}) {
        for (const auto& config : configs) {
            const uint32_t group = config.first, items = config.second;  // (clang: no captured bindings)
            penumbra::ScanOptions options;
            options.group_size = group;
            options.items_per_thread = items;
            options.allow_subgroups = subgroups;
            penumbra::Scanner scanner(options);
            CAPTURE(group);
            CAPTURE(items);
            CAPTURE(std::string(penumbra::scanSubgroupsName(scanner.subgroupMode())));
            const uint64_t block = uint64_t(group) * items;
            for (uint64_t n : {block - 1, block, block + 1, 3 * block * block / 2 + 5}) {
                if (n > (1u << 21)) n = (1u << 21) + 7;
                const std::vector<uint32_t> values = randomValues(rng, n);
                checkGpuScan(scanner, values, penumbra::ScanKind::Inclusive, false, 8, 4);
                checkGpuScan(scanner, values, penumbra::ScanKind::Exclusive, true, 48, 0);
            }
        }
    }
}

TEST_CASE("per-frame misuse returns a Status (after PENUMBRA_ASSERT) and touches no GL state") {
    context();
    penumbra::ScanOptions options;
    options.allow_subgroups = false;  // no construction self-check: reserved() starts at 0
    penumbra::Scanner scanner(options);
    penumbra::gl::Buffer a(4096), b(4096);
    const penumbra::BufferRange ra{a.id(), 0, 4096}, rb{b.id(), 0, 4096};
    penumbra::gl::Program marker = penumbra::gl::buildComputeProgram("penumbra/common/copy.comp.glsl");
    marker.use();
    auto expect = [&](penumbra::Status want, const penumbra::BufferRange& in, const penumbra::BufferRange& out,
                      uint64_t n) {
        CAPTURE(penumbra::statusName(want));
        CAPTURE(n);
        const int asserts = g_scan_test_asserts;
        CHECK(scanner.exclusive(in, out, n) == want);
        CHECK(g_scan_test_asserts == asserts + (want == penumbra::Status::Ok ? 0 : 1));
        // No GL call was made: the program stays the caller's.
        CHECK(static_cast<GLuint>(penumbra::gl::getInteger(GL_CURRENT_PROGRAM)) == marker.id());
    };
    // reserve() not called yet.
    CHECK(scanner.reserved() == 0);
    expect(penumbra::Status::NotReserved, ra, rb, 4);
    scanner.reserve(1000);
    CHECK(scanner.reserved() == 1000);
    expect(penumbra::Status::NotReserved, ra, rb, 1001);
    // Ranges.
    expect(penumbra::Status::RangeTooSmall, {0, 0, 4096}, rb, 4);
    expect(penumbra::Status::RangeTooSmall, ra, {b.id(), 0, 0}, 4);
    expect(penumbra::Status::RangeTooSmall, {a.id(), 0, 15}, rb, 4);
    expect(penumbra::Status::RangeTooSmall, ra, {b.id(), 16, 399}, 100);
    expect(penumbra::Status::Misaligned, {a.id(), 6, 400}, rb, 4);
    expect(penumbra::Status::Misaligned, ra, {b.id(), 2, 400}, 4);
    expect(penumbra::Status::InvalidArgument, {a.id(), 0, 40}, {a.id(), 4, 40}, 10);
    expect(penumbra::Status::InvalidArgument, {a.id(), 40, 44}, {a.id(), 0, 44}, 11);
    // n == 0 looks at nothing and succeeds.
    expect(penumbra::Status::Ok, {0, 3, 0}, {0, 5, 0}, 0);
    // A moved-from scanner reports NotReserved instead of touching freed objects.
    penumbra::Scanner moved(std::move(scanner));
    CHECK(moved.reserved() == 1000);
    CHECK(scanner.reserved() == 0);  // NOLINT(bugprone-use-after-move): checking the moved-from state
    expect(penumbra::Status::NotReserved, ra, rb, 4);
    // Touching but disjoint ranges in one buffer, and the identical range, are fine.
    CHECK(moved.exclusive({a.id(), 0, 40}, {a.id(), 40, 40}, 10) == penumbra::Status::Ok);
    CHECK(moved.exclusive({a.id(), 8, 40}, {a.id(), 8, 40}, 10) == penumbra::Status::Ok);
    glUseProgram(0);
    penumbra::gl::checkErrors("misuse");
}

TEST_CASE("load-time validation raises penumbra::Error naming the value") {
    penumbra::Scanner& scanner = defaultScanner();
    scanner.reserve(4096);
    penumbra::gl::Buffer a(1024), b(1024);
    GLuint no_storage = 0;
    glCreateBuffers(1, &no_storage);
    const GLuint never_created = 0x7ffffff0u;
    auto validate = [&](GLuint in, uint64_t in_off, GLuint out, uint64_t out_off, uint64_t n) {
        return errorOf([&] { scanner.validate({in, in_off, n * 4}, {out, out_off, n * 4}, n); });
    };
    CHECK(contains(validate(0, 0, b.id(), 0, 4), "input buffer 0 is not a buffer object"));
    CHECK(contains(validate(a.id(), 0, 0, 0, 4), "output buffer 0 is not a buffer object"));
    CHECK(contains(validate(never_created, 0, b.id(), 0, 4), "buffer 2147483632 is not a buffer object"));
    CHECK(contains(validate(no_storage, 0, b.id(), 0, 4), "has no storage (GL_BUFFER_SIZE 0"));
    CHECK(contains(validate(a.id(), 0, no_storage, 0, 4), "output buffer " + std::to_string(no_storage) + " has no storage"));
    CHECK(contains(validate(a.id(), 6, b.id(), 0, 4), "input offset 6 is not a multiple of 4"));
    CHECK(contains(validate(a.id(), 0, b.id(), 2, 4), "output offset 2 is not a multiple of 4"));
    CHECK(contains(validate(a.id(), 0, b.id(), 0, 257), "input range [0, +1028) exceeds"));
    CHECK(contains(validate(a.id(), 0, b.id(), 0, 257), "GL_BUFFER_SIZE 1024"));
    CHECK(contains(validate(a.id(), 4, b.id(), 0, 256), "input range [4, +1024) exceeds"));
    CHECK(contains(validate(a.id(), 0, b.id(), 1020, 2), "output range [1020, +8) exceeds"));
    CHECK(contains(validate(a.id(), 2048, b.id(), 0, 1), "[2048, +4)"));
    CHECK(contains(errorOf([&] { scanner.validate({a.id(), 0, 8}, {b.id(), 0, 400}, 100); }),
                   "input range holds 8 bytes, needs 400"));
    const uint64_t too_many = scanner.reserved() + 1;
    CHECK(contains(validate(a.id(), 0, b.id(), 0, too_many), "n = " + std::to_string(too_many) + " exceeds the reserved"));
    CHECK(contains(validate(a.id(), 0, a.id(), 4, 10), "input offset 0 and output offset 4"));
    CHECK(contains(validate(a.id(), 40, a.id(), 0, 11), "input offset 40 and output offset 0"));
    CHECK(validate(a.id(), 0, a.id(), 40, 10) == "(no penumbra::Error thrown)");
    CHECK(validate(a.id(), 8, a.id(), 8, 10) == "(no penumbra::Error thrown)");
    CHECK(validate(0, 3, 0, 5, 0) == "(no penumbra::Error thrown)");  // n == 0
    // Setup errors.
    CHECK(contains(errorOf([&] { scanner.reserve(penumbra::kScanMaxElements + 1); }), "n = 4294967296"));
    CHECK(contains(errorOf([&] { scanner.scratchBytes(penumbra::kScanMaxElements + 1); }), "n = 4294967296"));
    penumbra::ScanOptions bad;
    bad.group_size = 100;
    CHECK(contains(errorOf([&] { penumbra::Scanner s(bad); }), "group_size 100"));
    bad = {};
    bad.items_per_thread = 5;
    CHECK(contains(errorOf([&] { penumbra::Scanner s(bad); }), "items_per_thread 5"));
    penumbra::ScanBindings clash;
    clash.partials = clash.input;
    CHECK(contains(errorOf([&] { penumbra::Scanner s({}, penumbra::ShaderLibrary::embedded(), clash); }),
                   "ScanBindings::partials and input are both 0"));
    penumbra::ScanBindings far;
    far.output_vec4 = 100000;
    CHECK(contains(errorOf([&] { penumbra::Scanner s({}, penumbra::ShaderLibrary::embedded(), far); }),
                   "ScanBindings::output_vec4 100000"));
    far = {};
    far.constants = 100000;
    CHECK(contains(errorOf([&] { penumbra::Scanner s({}, penumbra::ShaderLibrary::embedded(), far); }),
                   "ScanBindings::constants 100000"));
    glDeleteBuffers(1, &no_storage);
    penumbra::gl::checkErrors("bad input");
}

TEST_CASE("GL state contract: nothing reset, foreign bindings and the engine's queued GL error survive") {
    context();
    penumbra::ScanOptions options;
    options.group_size = 64;
    options.items_per_thread = 4;
    penumbra::Scanner scanner(options);
    CHECK(scanner.scratchBytes(0) == 0);
    CHECK(scanner.scratchBytes(256) == 0);  // one block
    CHECK(scanner.scratchBytes(257) == scanner.plan(257).scratch_bytes);
    CHECK(scanner.scratchBytes(257) > 0);
    scanner.reserve(1u << 20);
    CHECK(scanner.scratchCapacity() >= scanner.scratchBytes(1u << 20));
    CHECK(scanner.scratchBuffer() != 0);
    CHECK(scanner.constantsBuffer() != 0);
    CHECK(scanner.constantsCapacity() >= scanner.plan(1u << 20).constants_bytes);

    // The scan's first barrier makes a shader write just before it visible: fill the input with a
    // compute copy and scan it with no barrier in between.
    const uint32_t seed = testSeed();
    std::mt19937 rng(seed);
    const size_t n = 100000;  // multiple of 4: the copy moves uvec4s
    const std::vector<uint32_t> values = randomValues(rng, n);
    penumbra::gl::Buffer source = penumbra::gl::Buffer::fromVector(values);
    penumbra::gl::Buffer input(n * 4), output(n * 4), foreign(256), foreign_ubo(256);
    input.fill(kPoison);
    output.fill(kPoison);
    penumbra::gl::Program copy = penumbra::gl::buildComputeProgram("penumbra/common/copy.comp.glsl");
    copy.use();
    glUniform1ui(copy.uniform("penumbraCopyCount"), static_cast<GLuint>(n / 4));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, source.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, input.id());
    const auto grid = penumbra::detail::foldDispatch(penumbra::detail::divUp(n / 4, 256));
    glDispatchCompute(grid.x, grid.y, 1);
    // The engine's state outside ScanBindings: bindings the scanner must not touch.
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 7, foreign.id());
    glBindBufferBase(GL_UNIFORM_BUFFER, 3, foreign_ubo.id());
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, foreign.id());  // generic bindings
    glBindBuffer(GL_UNIFORM_BUFFER, foreign_ubo.id());
    scanner.validate(rangeOf(input, 0, n), rangeOf(output, 0, n), n);
    penumbra::gl::checkErrors("before the queued error");
    // An error the engine queued before the scan (and has not read yet) must survive it.
    glBindBuffer(0xDEAD, 0);  // GL_INVALID_ENUM
    CHECK(scanner.inclusive(rangeOf(input, 0, n), rangeOf(output, 0, n), n) == penumbra::Status::Ok);
    CHECK(glGetError() == GL_INVALID_ENUM);
    CHECK(glGetError() == GL_NO_ERROR);
    // Not reset: the program is the scanner's last one (documented), not 0 ...
    const penumbra::ScanPlan plan = scanner.plan(n);
    const penumbra::ScanDispatch& last = plan.dispatch_list.back();
    CHECK(static_cast<GLuint>(penumbra::gl::getInteger(GL_CURRENT_PROGRAM)) == scanner.program(last.pass, last.vec4));
    // ... the bindings of ScanBindings are left pointing at what the last dispatch bound ...
    CHECK(static_cast<GLuint>(penumbra::gl::getInteger(GL_SHADER_STORAGE_BUFFER_BINDING, PENUMBRA_SCAN_BINDING_OUTPUT)) ==
          output.id());
    CHECK(static_cast<GLuint>(penumbra::gl::getInteger(GL_UNIFORM_BUFFER_BINDING, PENUMBRA_SCAN_BINDING_CONSTANTS)) ==
          scanner.constantsBuffer());
    // ... and everything else is the engine's, unchanged.
    CHECK(static_cast<GLuint>(penumbra::gl::getInteger(GL_SHADER_STORAGE_BUFFER_BINDING, 7)) == foreign.id());
    CHECK(static_cast<GLuint>(penumbra::gl::getInteger(GL_UNIFORM_BUFFER_BINDING, 3)) == foreign_ubo.id());
    CHECK(static_cast<GLuint>(penumbra::gl::getInteger(GL_SHADER_STORAGE_BUFFER_BINDING)) == foreign.id());
    CHECK(static_cast<GLuint>(penumbra::gl::getInteger(GL_UNIFORM_BUFFER_BINDING)) == foreign_ubo.id());
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    CHECK(firstMismatch(output.download<uint32_t>(), cpuScan(values, penumbra::ScanKind::Inclusive)) == "");

    // Own bindings: the programs' blocks follow ScanBindings; the default indices stay the engine's.
    penumbra::ScanBindings moved_bindings;
    moved_bindings.input = 5;
    moved_bindings.output = 6;
    moved_bindings.partials = 7;
    moved_bindings.input_vec4 = 1;
    moved_bindings.output_vec4 = 2;
    moved_bindings.constants = 4;
    // Setup does not drain the engine's GL errors either: construction (compiles, block bindings)
    // and reserve() (allocation checked by a GL_BUFFER_SIZE query) leave a queued error queued.
    glBindBuffer(0xDEAD, 0);  // GL_INVALID_ENUM
    penumbra::Scanner rebound(options, penumbra::ShaderLibrary::embedded(), moved_bindings);
    rebound.reserve(n);
    rebound.validate(rangeOf(source, 0, n), rangeOf(output, 0, n), n);
    CHECK(glGetError() == GL_INVALID_ENUM);
    CHECK(glGetError() == GL_NO_ERROR);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, foreign.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, foreign.id());
    glBindBufferBase(GL_UNIFORM_BUFFER, 0, foreign_ubo.id());
    output.fill(kPoison);
    CHECK(rebound.exclusive(rangeOf(source, 0, n), rangeOf(output, 0, n), n) == penumbra::Status::Ok);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    CHECK(firstMismatch(output.download<uint32_t>(), cpuScan(values, penumbra::ScanKind::Exclusive)) == "");
    for (GLuint b : {0u, 3u}) {
        CAPTURE(b);
        CHECK(static_cast<GLuint>(penumbra::gl::getInteger(GL_SHADER_STORAGE_BUFFER_BINDING, b)) == foreign.id());
    }
    CHECK(static_cast<GLuint>(penumbra::gl::getInteger(GL_UNIFORM_BUFFER_BINDING, 0)) == foreign_ubo.id());
    CHECK(static_cast<GLuint>(penumbra::gl::getInteger(GL_UNIFORM_BUFFER_BINDING, 4)) == rebound.constantsBuffer());

    // Moves transfer the programs and the buffers; the moved-from scanner owns nothing.
    const GLuint scratch = scanner.scratchBuffer();
    penumbra::Scanner moved(std::move(scanner));
    CHECK(moved.scratchBuffer() == scratch);
    CHECK(scanner.scratchBuffer() == 0);  // NOLINT(bugprone-use-after-move): checking the moved-from state
    CHECK(scanner.constantsBuffer() == 0);
    output.fill(kPoison);
    CHECK(moved.exclusive(rangeOf(source, 0, n), rangeOf(output, 0, n), n) == penumbra::Status::Ok);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    CHECK(firstMismatch(output.download<uint32_t>(), cpuScan(values, penumbra::ScanKind::Exclusive)) == "");
    penumbra::Scanner assigned;
    assigned = std::move(moved);
    CHECK(assigned.scratchBuffer() == scratch);
    CHECK(glIsBuffer(scratch));
    glUseProgram(0);
    for (GLuint b = 0; b < 8; ++b) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b, 0);
    for (GLuint b = 0; b < 5; ++b) glBindBufferBase(GL_UNIFORM_BUFFER, b, 0);
    penumbra::gl::checkErrors("state contract");
}

TEST_CASE("workgroup.glsl through its hook in a test-only kernel") {
    context();
    const penumbra::ShaderLibrary lib = penumbra::test::catalogLibrary();
    const uint32_t seed = testSeed();
    std::mt19937 rng(seed);
    struct Variant {
        const char* key;
        uint32_t group_size;
        bool two_d;
    };
    std::vector<Variant> variants = {{"scan_workgroup_test.comp.glsl", 1, false},
                                     {"scan_workgroup_test.comp.glsl", 32, false},
                                     {"scan_workgroup_test.comp.glsl", 100, false},
                                     {"scan_workgroup_test.comp.glsl", 256, false},
                                     {"scan_workgroup_test.comp.glsl", 257, false},
                                     {"scan_workgroup_test.comp.glsl", 1024, false},
                                     {"scan_workgroup_test.comp.glsl", 64, true}};
    if (penumbra::detail::computeSubgroupSize() != 0) {
        for (uint32_t size : {32u, 256u, 1024u}) variants.push_back({"scan_workgroup_subgroups_test.comp.glsl", size, false});
    } else {
        MESSAGE("no GL_KHR_shader_subgroup arithmetic on ", context().renderer(),
                ": its variant is only validated by glslangValidator");
    }
    if (penumbra::detail::glHasExtension("GL_ARB_shader_ballot")) {
        for (uint32_t size : {32u, 256u, 1024u}) variants.push_back({"scan_workgroup_ballot_test.comp.glsl", size, false});
        variants.push_back({"scan_workgroup_ballot_test.comp.glsl", 64, true});
    } else {
        MESSAGE("no GL_ARB_shader_ballot on ", context().renderer(), ": its variant is only validated by glslangValidator");
    }
    const uint32_t groups = 3;
    for (const Variant& v : variants) {
        CAPTURE(v.key);
        CAPTURE(v.group_size);
        CAPTURE(v.two_d);
        penumbra::ShaderDefines defines = {{"PENUMBRA_SCAN_GROUP_SIZE", std::to_string(v.group_size)}};
        if (v.two_d) defines.push_back({"PENUMBRA_SCAN_TEST_2D", ""});
        penumbra::gl::Program program = penumbra::gl::buildComputeProgram(v.key, defines, lib);
        const size_t n = size_t(groups) * v.group_size;
        std::vector<uint32_t> values = randomValues(rng, n);
        penumbra::gl::Buffer in = penumbra::gl::Buffer::fromVector(values);
        penumbra::gl::Buffer out(n * 6 * 4);
        out.fill(kPoison);
        program.use();
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, in.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, out.id());
        glDispatchCompute(groups, 1, 1);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        const std::vector<uint32_t> got = out.download<uint32_t>();
        std::vector<uint32_t> want(n * 6);
        for (uint32_t g = 0; g < groups; ++g) {
            uint32_t ex = 0, in3 = 0, red = 0, total = 0, total3 = 0, plain = 0;
            for (uint32_t i = 0; i < v.group_size; ++i) {
                total += values[g * v.group_size + i];
                total3 += 3u * values[g * v.group_size + i];
                red += values[g * v.group_size + i] ^ 0x80000000u;
            }
            for (uint32_t i = 0; i < v.group_size; ++i) {
                const size_t e = size_t(g) * v.group_size + i;
                in3 += 3u * values[e];
                want[6 * e + 0] = ex;
                want[6 * e + 1] = total;
                want[6 * e + 2] = in3;
                want[6 * e + 3] = total3;
                want[6 * e + 4] = red;
                want[6 * e + 5] = plain;
                ex += values[e];
                plain += values[e] + 1u;
            }
        }
        CHECK(firstMismatch(got, want) == "");
        penumbra::gl::checkErrors("workgroup kernel");
    }
    // A kernel that forgets the hook gets a compile error naming it.
    const std::string error = errorOf([&] { penumbra::gl::buildComputeProgram("scan_workgroup_test.comp.glsl", {}, lib); });
    INFO(error);
    CHECK(contains(error, "PENUMBRA_SCAN_GROUP_SIZE"));
    CHECK(contains(error, "penumbra/scan/workgroup.glsl"));
}

TEST_CASE("workgroup.glsl: a hook that disagrees with local_size_x fails to compile instead of summing wrong") {
    context();
    const penumbra::ShaderLibrary lib = penumbra::test::catalogLibrary();
    // The same text compiles when the hook and the layout agree ...
    CHECK(errorOf([&] {
              penumbra::gl::buildComputeProgram("scan_workgroup_test.comp.glsl",
                                                {{"PENUMBRA_SCAN_GROUP_SIZE", "64"}, {"PENUMBRA_SCAN_TEST_LOCAL_SIZE", "64"}},
                                                lib);
          }) == "(no penumbra::Error thrown)");
    // ... and fails when they do not, in either direction, and in 2D.
    for (const char* local : {"32", "128"}) {
        CAPTURE(local);
        const std::string error = errorOf([&] {
            penumbra::gl::buildComputeProgram("scan_workgroup_test.comp.glsl",
                                              {{"PENUMBRA_SCAN_GROUP_SIZE", "64"}, {"PENUMBRA_SCAN_TEST_LOCAL_SIZE", local}},
                                              lib);
        });
        INFO(error);
        CHECK(contains(error, "failed to compile"));
        // The message is the driver's: Mesa "array size must be > 0" at the check's line (annotated
        // with workgroup.glsl's line even where Mesa reports source string 0: the line numbers
        // carry the file); glslang names penumbraScanGroupSizeMustEqualLocalSize; NVIDIA "size of
        // dimension cannot be less than 1" annotated with the check's lines of workgroup.glsl (59-60).
        CHECK((contains(error, "array size") || contains(error, "penumbraScanGroupSizeMustEqualLocalSize") ||
               contains(error, "penumbra/scan/workgroup.glsl:59]") || contains(error, "penumbra/scan/workgroup.glsl:60]")));
    }
    // Including the snippet before the layout line cannot be checked, so it is an error too.
    penumbra::ShaderLibrary first_lib = lib;
    first_lib.add("scan_include_first_test.comp.glsl",
                  "#define PENUMBRA_SCAN_GROUP_SIZE 64\n"
                  "#include \"penumbra/scan/workgroup.glsl\"\n"
                  "layout(local_size_x = 64) in;\n"
                  "layout(std430, binding = 0) buffer B { uint b[]; };\n"
                  "void main() { b[gl_LocalInvocationIndex] = penumbraScanWorkgroupExclusive(1u); }\n");
    const std::string first =
        errorOf([&] { penumbra::gl::buildComputeProgram("scan_include_first_test.comp.glsl", {}, first_lib); });
    INFO(first);
    CHECK(contains(first, "failed to compile"));
    // The scan kernel's own hook is the same define as its layout line: it always agrees.
    penumbra::gl::checkErrors("group-size mismatch");
}


// ---- Every GL call and heap allocation inside scan(), recorded --------------------------------
//
// A wrapping loader: glad 2 calls GL through global function pointers (glad_glGetError, ...), so
// the test swaps them for counting wrappers; a replaced global operator new counts allocations.
#ifdef GLAD_GL_H_
namespace {

bool g_recording = false;
size_t g_allocations = 0;

constexpr int kMaxHooks = 64;
struct HookEntry {
    const char* name = nullptr;
    bool forbidden = false;  // a query, error read, read-back, map or wait
    int calls = 0;
};
std::array<HookEntry, kMaxHooks> g_hooks;
int g_hook_count = 0;

template <auto* Slot, typename Fn = std::remove_pointer_t<decltype(Slot)>>
struct GlHook;
template <auto* Slot, typename R, typename... A>
struct GlHook<Slot, R(GLAD_API_PTR*)(A...)> {
    static inline R(GLAD_API_PTR* original)(A...) = nullptr;
    static inline int index = -1;
    static R GLAD_API_PTR hook(A... a) {
        if (g_recording) ++g_hooks[index].calls;
        return original(a...);
    }
    static void install(const char* name, bool forbidden) {
        if (!*Slot || index >= 0) return;  // entry point missing in this context, or installed
        index = g_hook_count++;
        g_hooks[index].name = name;
        g_hooks[index].forbidden = forbidden;
        original = *Slot;
        *Slot = &hook;
    }
};

#define PENUMBRA_TEST_HOOK(fn, forbidden) GlHook<&glad_##fn>::install(#fn, forbidden)

void installGlHooks() {
    // Forbidden in a per-frame call: queries, error reads, read-backs, maps, waits.
    PENUMBRA_TEST_HOOK(glGetError, true);
    PENUMBRA_TEST_HOOK(glGetIntegerv, true);
    PENUMBRA_TEST_HOOK(glGetInteger64v, true);
    PENUMBRA_TEST_HOOK(glGetIntegeri_v, true);
    PENUMBRA_TEST_HOOK(glGetInteger64i_v, true);
    PENUMBRA_TEST_HOOK(glGetBooleanv, true);
    PENUMBRA_TEST_HOOK(glGetFloatv, true);
    PENUMBRA_TEST_HOOK(glGetString, true);
    PENUMBRA_TEST_HOOK(glGetStringi, true);
    PENUMBRA_TEST_HOOK(glGetNamedBufferParameteriv, true);
    PENUMBRA_TEST_HOOK(glGetNamedBufferParameteri64v, true);
    PENUMBRA_TEST_HOOK(glGetBufferParameteriv, true);
    PENUMBRA_TEST_HOOK(glIsBuffer, true);
    PENUMBRA_TEST_HOOK(glIsProgram, true);
    PENUMBRA_TEST_HOOK(glGetProgramiv, true);
    PENUMBRA_TEST_HOOK(glGetUniformLocation, true);
    PENUMBRA_TEST_HOOK(glGetUniformBlockIndex, true);
    PENUMBRA_TEST_HOOK(glGetProgramResourceIndex, true);
    PENUMBRA_TEST_HOOK(glGetNamedBufferSubData, true);
    PENUMBRA_TEST_HOOK(glGetBufferSubData, true);
    PENUMBRA_TEST_HOOK(glMapBuffer, true);
    PENUMBRA_TEST_HOOK(glMapBufferRange, true);
    PENUMBRA_TEST_HOOK(glMapNamedBuffer, true);
    PENUMBRA_TEST_HOOK(glMapNamedBufferRange, true);
    PENUMBRA_TEST_HOOK(glFinish, true);
    PENUMBRA_TEST_HOOK(glFenceSync, true);
    PENUMBRA_TEST_HOOK(glClientWaitSync, true);
    PENUMBRA_TEST_HOOK(glGetQueryObjectuiv, true);
    PENUMBRA_TEST_HOOK(glGetQueryObjectui64v, true);
    // Allowed; counted to check the recording itself.
    PENUMBRA_TEST_HOOK(glDispatchCompute, false);
    PENUMBRA_TEST_HOOK(glMemoryBarrier, false);
    PENUMBRA_TEST_HOOK(glUseProgram, false);
    PENUMBRA_TEST_HOOK(glBindBuffersRange, false);
    PENUMBRA_TEST_HOOK(glBindBufferRange, false);
    PENUMBRA_TEST_HOOK(glBindBufferBase, false);
    PENUMBRA_TEST_HOOK(glBindBuffer, false);
    PENUMBRA_TEST_HOOK(glNamedBufferSubData, false);
    PENUMBRA_TEST_HOOK(glNamedBufferStorage, false);
    PENUMBRA_TEST_HOOK(glCreateBuffers, false);
}

int hookCalls(const char* name) {
    for (int i = 0; i < g_hook_count; ++i) {
        if (std::string(g_hooks[i].name) == name) return g_hooks[i].calls;
    }
    return -1;
}

void resetHooks() {
    for (int i = 0; i < g_hook_count; ++i) g_hooks[i].calls = 0;
    g_allocations = 0;
}

}  // namespace

void* operator new(std::size_t size) {
    if (g_recording) ++g_allocations;
    if (void* p = std::malloc(size ? size : 1)) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
    if (g_recording) ++g_allocations;
    if (void* p = std::malloc(size ? size : 1)) return p;
    throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

TEST_CASE("scan() after warm-up: 0 queries, 0 glGetError, 0 read-backs/maps/waits, 0 heap allocations") {
    context();
    installGlHooks();
    REQUIRE(hookCalls("glGetError") == 0);  // installed
    penumbra::ScanOptions windowed;
    windowed.group_size = 32;
    windowed.items_per_thread = 4;
    windowed.window_elements = 3 * 128;
    penumbra::Scanner small(windowed);
    penumbra::Scanner& big = defaultScanner();
    const uint64_t max_n = (1u << 20) + 3;
    penumbra::gl::Buffer a(max_n * 4 + 64), b(max_n * 4 + 64);
    big.reserve(max_n);
    small.reserve(20000);
    struct Run {
        penumbra::Scanner* scanner;
        penumbra::ScanKind kind;
        penumbra::BufferRange in, out;
        uint64_t n;
    };
    const Run runs[] = {
        {&big, penumbra::ScanKind::Exclusive, {a.id(), 0, max_n * 4}, {b.id(), 0, max_n * 4}, max_n},
        {&big, penumbra::ScanKind::Inclusive, {a.id(), 4, 40000}, {b.id(), 40, 40000}, 10000},
        {&big, penumbra::ScanKind::Exclusive, {a.id(), 16, 4}, {a.id(), 16, 4}, 1},
        {&small, penumbra::ScanKind::Inclusive, {a.id(), 8, 80000}, {b.id(), 12, 80000}, 19999},
    };
    for (const Run& r : runs) {
        CAPTURE(r.n);
        CAPTURE(r.in.offset);
        r.scanner->validate(r.in, r.out, r.n);                                    // load time
        CHECK(r.scanner->scan(r.kind, r.in, r.out, r.n) == penumbra::Status::Ok);  // warm-up
        const uint64_t dispatches = r.scanner->plan(r.kind, r.in, r.out, r.n).dispatches;
        resetHooks();
        g_recording = true;
        const penumbra::Status status = r.scanner->scan(r.kind, r.in, r.out, r.n);
        g_recording = false;
        CHECK(status == penumbra::Status::Ok);
        CHECK(g_allocations == 0);
        for (int i = 0; i < g_hook_count; ++i) {
            if (g_hooks[i].forbidden && g_hooks[i].calls != 0) FAIL(g_hooks[i].name, " called ", g_hooks[i].calls, " times");
        }
        CHECK(hookCalls("glDispatchCompute") == static_cast<int>(dispatches));
        CHECK(hookCalls("glMemoryBarrier") == static_cast<int>(dispatches));
        CHECK(hookCalls("glNamedBufferSubData") == 1);  // all constants in one upload
        CHECK(hookCalls("glBindBufferBase") == 0);
        CHECK(hookCalls("glBindBuffer") == 0);
        CHECK(hookCalls("glBindBufferRange") == 0);  // glBindBuffersRange: generic bindings untouched
        CHECK(hookCalls("glBindBuffersRange") > 0);
        CHECK(hookCalls("glNamedBufferStorage") == 0);
        CHECK(hookCalls("glCreateBuffers") == 0);
        CHECK(hookCalls("glUseProgram") <= static_cast<int>(dispatches));
    }
    // Misuse: a Status and no GL call at all.
    resetHooks();
    g_recording = true;
    const int asserts = g_scan_test_asserts;
    const penumbra::Status refused = big.exclusive({a.id(), 0, 4}, {b.id(), 0, 4}, 2);
    g_recording = false;
    CHECK(refused == penumbra::Status::RangeTooSmall);
    CHECK(g_scan_test_asserts == asserts + 1);
    int total = 0;
    for (int i = 0; i < g_hook_count; ++i) total += g_hooks[i].calls;
    CHECK(total == 0);
    CHECK(g_allocations == 0);
    penumbra::gl::checkErrors("recorded scans");
}

#endif

TEST_SUITE("stress") {
    TEST_CASE("GPU scan of 2^26 + 5 and 2^28 elements (windows of GL_MAX_SHADER_STORAGE_BLOCK_SIZE)") {
        penumbra::Scanner& scanner = defaultScanner();
        const uint32_t seed = testSeed();
        std::mt19937 rng(seed);
        for (uint64_t n : {(uint64_t(1) << 26) + 5, uint64_t(1) << 28}) {
            const auto start = std::chrono::steady_clock::now();
            const std::vector<uint32_t> values = randomValues(rng, n);
            MESSAGE("n = ", n, ": ", scanner.plan(n).windows, " windows, ", scanner.plan(n).dispatches, " dispatches");
            checkGpuScan(scanner, values, penumbra::ScanKind::Exclusive, true, 4, 0);
            if (n < (uint64_t(1) << 28)) checkGpuScan(scanner, values, penumbra::ScanKind::Inclusive, false, 16, 12);
            MESSAGE("n = ", n, " took ",
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), " s");
        }
    }
}
