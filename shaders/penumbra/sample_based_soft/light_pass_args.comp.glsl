// penumbra — sample-based soft shadows, deferred pairs: after light-pass draws, decides what the
// compute pass light_pass.comp.glsl works. When the fragments that did not fit the pairs buffer
// fit the fragments buffer (PENUMBRA_SBS_ARGS_FRAGMENT_CAPACITY) and every fragment's triangle had
// a slot, it writes glDispatchComputeIndirect's group counts for the pairs (at most
// PENUMBRA_SBS_ARGS_CAPACITY) and for those fragments, and adds the draws' waiting counters to the
// work counters; otherwise (overflow) it dispatches nothing, drops the waiting counters and sets
// the fallback flag, on which the pipeline draws the same draws again with the
// fragment-stage program (its list-block predicates read the flag: blocks.frag.glsl). Then it
// resets the append counters for the next draws. One invocation. PENUMBRA_SBS_ARGS_KIND=1 and 2:
// the same for the exact-test pass (light_pass_tests.comp.glsl) and the tables pass
// (light_pass_tables.comp.glsl), after the passes that fill their buffers: the entries appended, up
// to the capacity PENUMBRA_SBS_ARGS_CAPACITY (requests past it wrote no work); kind 3 the same for
// the coverage pass (light_pass_coverage.comp.glsl) after the draws, before kind 0 (the records
// past its capacity were drawn); kind 4 (the compute light pass, after kind 0): the coverage pass's
// group counts again for its program that works the pairs itself, when kind 0 found an overflow
// (else 0 groups): PENUMBRA_SBS_INLINE_PARTS workgroups per (record, tile) item of
// PENUMBRA_SBS_TILE_ROWS x PENUMBRA_SBS_TILE_COLUMNS texels; kind 5 (after the
// coverage pass's tile counts and their scan): its (record, tile) items and group counts, folded
// into x and y. Kind 3 with PENUMBRA_SBS_ARGS_ROUND=1 (the compute light pass, first of a run of
// the deferred passes): when nothing waits for them (no record, slot, pair, fragment or setup count
// since their last run, as after setup runs of list blocks no list reaches) it zeroes every pass's
// group counts and the round's (PENUMBRA_SBS_DEFERRAL_ROUND_ARGS), with which the host dispatches
// the run's other one-invocation programs and the scan: an idle run costs one invocation; a run
// with work adds one to PENUMBRA_SBS_WORK_CHUNKS (with or without PENUMBRA_SBS_COUNT_WORK).
// Windows (the compute light pass, PENUMBRA_SBS_ARGS_WINDOWS > 0: kinds 0 and 3): when a run's
// pairs and fragments overflow, kind 0 works none of them and splits the run into
// PENUMBRA_SBS_DEFERRAL_SPLIT windows, as many as the fragments asked for fill the fragments
// buffer, plus one (at most PENUMBRA_SBS_ARGS_WINDOWS); the host then runs the deferred passes once
// per window (uniform penumbraSbsWindow = k + 1; 0: the run itself; 0xFFFFFFFF: a run no windows
// follow, whose overflow is worked inline), each over the records
// r % SPLIT == k (the coverage pass's count program leaves out the others), windows past SPLIT
// idle. Only a window that overflows too is worked by the coverage pass's inline program
// (PENUMBRA_SBS_WORK_FALLBACKS); the bits are the same either way.
// penumbra-permutation: PENUMBRA_SBS_COUNT_WORK=1 PENUMBRA_SBS_ARGS_CAPACITY=1024u PENUMBRA_SBS_ARGS_FRAGMENT_CAPACITY=256u
// penumbra-permutation: PENUMBRA_SBS_COUNT_WORK=0
// penumbra-permutation: PENUMBRA_SBS_COUNT_WORK=1 PENUMBRA_SBS_ARGS_WINDOWS=8 PENUMBRA_SBS_ARGS_CAPACITY=1024u PENUMBRA_SBS_ARGS_FRAGMENT_CAPACITY=256u
// penumbra-permutation: PENUMBRA_SBS_ARGS_KIND=1 PENUMBRA_SBS_ARGS_CAPACITY=1024u
// penumbra-permutation: PENUMBRA_SBS_ARGS_KIND=2 PENUMBRA_SBS_ARGS_CAPACITY=1024u
// penumbra-permutation: PENUMBRA_SBS_ARGS_KIND=3 PENUMBRA_SBS_ARGS_CAPACITY=1024u
// penumbra-permutation: PENUMBRA_SBS_ARGS_KIND=3 PENUMBRA_SBS_ARGS_CAPACITY=1024u PENUMBRA_SBS_ARGS_ROUND=1
// penumbra-permutation: PENUMBRA_SBS_ARGS_KIND=3 PENUMBRA_SBS_ARGS_CAPACITY=1024u PENUMBRA_SBS_ARGS_ROUND=1 PENUMBRA_SBS_COUNT_WORK=0
// penumbra-permutation: PENUMBRA_SBS_ARGS_KIND=3 PENUMBRA_SBS_ARGS_CAPACITY=1024u PENUMBRA_SBS_ARGS_ROUND=1 PENUMBRA_SBS_ARGS_WINDOWS=8
// penumbra-permutation: PENUMBRA_SBS_ARGS_KIND=4 PENUMBRA_SBS_TILE_ROWS=8u PENUMBRA_SBS_TILE_COLUMNS=32u
// penumbra-permutation: PENUMBRA_SBS_ARGS_KIND=5 PENUMBRA_SBS_REGION_CAPACITY=64u PENUMBRA_SBS_TILE_BASE=0u
#include "penumbra/sample_based_soft/sample_based_soft_shared.h"

#ifndef PENUMBRA_SBS_COUNT_WORK
#define PENUMBRA_SBS_COUNT_WORK 1
#endif

layout(local_size_x = 1) in;

layout(std430, binding = PENUMBRA_SBS_DEFERRAL_BINDING) buffer PenumbraSbsDeferral { uint penumbraSbsDeferral[]; };
#ifndef PENUMBRA_SBS_ARGS_ROUND
#define PENUMBRA_SBS_ARGS_ROUND 0
#endif
#if PENUMBRA_SBS_COUNT_WORK || PENUMBRA_SBS_ARGS_ROUND
layout(std430, binding = PENUMBRA_SBS_WORK_BINDING) buffer PenumbraSbsWork { uint penumbraSbsWork[]; };
#endif

#ifndef PENUMBRA_SBS_ARGS_KIND
#define PENUMBRA_SBS_ARGS_KIND 0  // 0: the pairs' compute pass, 1: the exact-test pass, 2: the tables pass
#endif
#ifndef PENUMBRA_SBS_ARGS_CAPACITY
#define PENUMBRA_SBS_ARGS_CAPACITY 0u  // SampleBasedSoftGpuOptions::deferred_pairs, deferred_tests, deferred_pairs
#endif
#ifndef PENUMBRA_SBS_ARGS_FRAGMENT_CAPACITY
#define PENUMBRA_SBS_ARGS_FRAGMENT_CAPACITY 0u  // kind 0: SampleBasedSoftGpuOptions::deferred_fragments
#endif
#if PENUMBRA_SBS_ARGS_KIND == 1
#define PENUMBRA_SBS_ARGS_COUNTER PENUMBRA_SBS_DEFERRAL_TESTS
#define PENUMBRA_SBS_ARGS_DISPATCHED PENUMBRA_SBS_DEFERRAL_TESTS_DISPATCHED
#define PENUMBRA_SBS_ARGS_WORDS PENUMBRA_SBS_DEFERRAL_TEST_ARGS
#elif PENUMBRA_SBS_ARGS_KIND == 2
#define PENUMBRA_SBS_ARGS_COUNTER PENUMBRA_SBS_DEFERRAL_SAMPLES
#define PENUMBRA_SBS_ARGS_DISPATCHED PENUMBRA_SBS_DEFERRAL_SAMPLES_DISPATCHED
#define PENUMBRA_SBS_ARGS_WORDS PENUMBRA_SBS_DEFERRAL_SAMPLE_ARGS
#elif PENUMBRA_SBS_ARGS_KIND == 3
#define PENUMBRA_SBS_ARGS_COUNTER PENUMBRA_SBS_DEFERRAL_REGIONS
#define PENUMBRA_SBS_ARGS_DISPATCHED PENUMBRA_SBS_DEFERRAL_REGIONS_DISPATCHED
#define PENUMBRA_SBS_ARGS_WORDS PENUMBRA_SBS_DEFERRAL_REGION_ARGS
#define PENUMBRA_SBS_ARGS_GROUP PENUMBRA_SBS_COVERAGE_GROUP
#endif
#ifndef PENUMBRA_SBS_ARGS_GROUP
#define PENUMBRA_SBS_ARGS_GROUP PENUMBRA_SBS_DEFERRAL_GROUP
#endif

#ifndef PENUMBRA_SBS_ARGS_WINDOWS
#define PENUMBRA_SBS_ARGS_WINDOWS 0  // kinds 0 and 3 (compute light pass): the most windows an overflowed run is split into
#endif
#if PENUMBRA_SBS_ARGS_WINDOWS > 0
layout(location = 0) uniform uint penumbraSbsWindow;  // 0: a run; k + 1: window k of the last run; ~0u: a run without windows
#endif

#if PENUMBRA_SBS_ARGS_KIND == 5
// The coverage pass's tile counts and first items (light_pass_coverage.comp.glsl).
layout(std430, binding = PENUMBRA_SBS_TRIANGLES_BINDING) readonly buffer PenumbraSbsTriangles { uint penumbraSbsTriangles[]; };
#endif

#if PENUMBRA_SBS_ARGS_KIND == 4 || PENUMBRA_SBS_ARGS_KIND == 5
// The group counts of `groups` workgroups at deferral word `words`, folded into x and y (at most
// 65 535 per dimension, GL's minimum); the programs index their groups y * x + x.
void penumbraSbsFoldedArgs(uint words, uint groups) {
    const uint x = min(groups, 65535u);
    penumbraSbsDeferral[words] = x;
    penumbraSbsDeferral[words + 1u] = x == 0u ? 1u : (groups + x - 1u) / x;
    penumbraSbsDeferral[words + 2u] = 1u;
}
#endif

void main() {
#if PENUMBRA_SBS_ARGS_KIND == 4
    // The inline program's workgroups (its tile's texels the invocations), none without an
    // overflow.
    const bool overflow = penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_FALLBACK] != 0u;
    const uint items = overflow ? penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_ITEMS_DISPATCHED] : 0u;
    const uint parts = PENUMBRA_SBS_INLINE_PARTS(PENUMBRA_SBS_TILE_ROWS * PENUMBRA_SBS_TILE_COLUMNS);
    penumbraSbsFoldedArgs(PENUMBRA_SBS_DEFERRAL_INLINE_ARGS, items * parts);
#elif PENUMBRA_SBS_ARGS_KIND == 5
    const uint records = penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_REGIONS_DISPATCHED];
    const uint counts = uint(PENUMBRA_SBS_TILE_BASE), firsts = counts + 3u * uint(PENUMBRA_SBS_REGION_CAPACITY);
    const uint items = records == 0u ? 0u : penumbraSbsTriangles[firsts + records - 1u] + penumbraSbsTriangles[counts + records - 1u];
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_ITEMS_DISPATCHED] = items;
    const uint group = uint(PENUMBRA_SBS_COVERAGE_GROUP);
    penumbraSbsFoldedArgs(PENUMBRA_SBS_DEFERRAL_REGION_ARGS, (items + group - 1u) / group);
#elif PENUMBRA_SBS_ARGS_KIND != 0
#if PENUMBRA_SBS_ARGS_ROUND
#if PENUMBRA_SBS_ARGS_WINDOWS > 0
    // Window k of the last run: work waits when that run split into more than k windows; its
    // records stay as they are (the count program picks the window's).
    const bool window = penumbraSbsWindow != 0u && penumbraSbsWindow != 0xFFFFFFFFu;
    const bool waiting = window ? penumbraSbsWindow <= penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SPLIT] :
#else
    const bool window = false;
    const bool waiting =
#endif
                         penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_REGIONS] != 0u || penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_TRIANGLES] != 0u ||
                         penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_PAIRS] != 0u || penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_FRAGMENTS] != 0u ||
                         penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_OVERFLOW] != 0u || penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SETUP] != 0u ||
                         penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SETUP + 1] != 0u;
    if (!window) penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SPLIT] = 0u;  // a new run: no window of the last one waits
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_ROUND_ARGS] = waiting ? 1u : 0u;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_ROUND_ARGS + 1] = 1u;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_ROUND_ARGS + 2] = 1u;
    if (waiting) penumbraSbsWork[PENUMBRA_SBS_WORK_CHUNKS] += 1u;
    if (!waiting) {  // the run's programs that read their group counts from these find none
        penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_ARGS] = 0u;
        penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_FRAGMENT_ARGS] = 0u;
        penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_INLINE_ARGS] = 0u;
        penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SAMPLE_ARGS] = 0u;
        penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_TEST_ARGS] = 0u;
    }
#endif
#if PENUMBRA_SBS_ARGS_ROUND
    // A window reads the run's records again.
    const uint entries = !waiting ? 0u : window ? penumbraSbsDeferral[PENUMBRA_SBS_ARGS_DISPATCHED]
                                               : min(penumbraSbsDeferral[PENUMBRA_SBS_ARGS_COUNTER], uint(PENUMBRA_SBS_ARGS_CAPACITY));
#else
    const uint entries = min(penumbraSbsDeferral[PENUMBRA_SBS_ARGS_COUNTER], uint(PENUMBRA_SBS_ARGS_CAPACITY));
#endif
    penumbraSbsDeferral[PENUMBRA_SBS_ARGS_DISPATCHED] = entries;
    penumbraSbsDeferral[PENUMBRA_SBS_ARGS_WORDS] = (entries + uint(PENUMBRA_SBS_ARGS_GROUP) - 1u) / uint(PENUMBRA_SBS_ARGS_GROUP);
    penumbraSbsDeferral[PENUMBRA_SBS_ARGS_WORDS + 1] = 1u;
    penumbraSbsDeferral[PENUMBRA_SBS_ARGS_WORDS + 2] = 1u;
    penumbraSbsDeferral[PENUMBRA_SBS_ARGS_COUNTER] = 0u;
#else
    const uint pairs = min(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_PAIRS], uint(PENUMBRA_SBS_ARGS_CAPACITY));
    const uint fragments = penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_FRAGMENTS];
    const bool overflow = fragments > uint(PENUMBRA_SBS_ARGS_FRAGMENT_CAPACITY) ||
                          penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_OVERFLOW] != 0u;
#if PENUMBRA_SBS_ARGS_WINDOWS > 0
    // A run (not a window) that overflows is split into windows instead of worked inline: as
    // many as its fragments fill the fragments buffer, plus one for what the pairs buffer held.
    const bool split = overflow && penumbraSbsWindow == 0u;
    if (split)
        penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SPLIT] =
            min(uint(PENUMBRA_SBS_ARGS_WINDOWS), (fragments + uint(PENUMBRA_SBS_ARGS_FRAGMENT_CAPACITY) - 1u) / uint(PENUMBRA_SBS_ARGS_FRAGMENT_CAPACITY) + 1u);
#else
    const bool split = false;
#endif
    const uint dispatched = overflow ? 0u : pairs, fragments_dispatched = overflow ? 0u : fragments;
    const uint group = uint(PENUMBRA_SBS_DEFERRAL_GROUP);
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_DISPATCHED] = dispatched;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_ARGS] = (dispatched + group - 1u) / group;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_ARGS + 1] = 1u;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_ARGS + 2] = 1u;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_FRAGMENTS_DISPATCHED] = fragments_dispatched;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_FRAGMENT_ARGS] = (fragments_dispatched + group - 1u) / group;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_FRAGMENT_ARGS + 1] = 1u;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_FRAGMENT_ARGS + 2] = 1u;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_FALLBACK] = overflow && !split ? 1u : 0u;
    for (uint i = 0u; i < uint(PENUMBRA_SBS_WORK_WORDS); ++i) {
#if PENUMBRA_SBS_COUNT_WORK
        if (!overflow) penumbraSbsWork[i] += penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_PENDING + i];
#endif
        penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_PENDING + i] = 0u;
    }
#if PENUMBRA_SBS_COUNT_WORK
    // The pairs dispatched but the straddling fragment's empty ones (the per-fragment pass counts
    // its own).
    if (!overflow) penumbraSbsWork[PENUMBRA_SBS_WORK_DEFERRED] += dispatched - penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_EMPTY];
    if (overflow && !split) penumbraSbsWork[PENUMBRA_SBS_WORK_FALLBACKS] += 1u;
    // The compute light pass's setup counts, overflow or not.
    penumbraSbsWork[PENUMBRA_SBS_WORK_TRIANGLES_CULLED] += penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SETUP];
    penumbraSbsWork[PENUMBRA_SBS_WORK_BAD_INDICES] += penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SETUP + 1];
#endif
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SETUP] = 0u;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SETUP + 1] = 0u;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_PAIRS] = 0u;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_FRAGMENTS] = 0u;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_EMPTY] = 0u;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_TRIANGLES] = 0u;
    penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_OVERFLOW] = 0u;
#endif
}
