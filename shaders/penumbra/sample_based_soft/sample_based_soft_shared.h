// penumbra — constants and the parameter block shared by the sample-based soft-shadow pipeline's
// host code (include/penumbra/pipelines/sample_based_soft.hpp, gl/pipelines/sample_based_soft.hpp)
// and its shaders (light_pass.*, blocks.frag.glsl, resolve.comp.glsl). Valid GLSL and C++.
#ifndef PENUMBRA_SAMPLE_BASED_SOFT_SHARED_H
#define PENUMBRA_SAMPLE_BASED_SOFT_SHARED_H

// Bindings: the defaults of penumbra::SbsBindings, injected as defines (each overridable). The
// influence region's parameter block is a uniform block at PENUMBRA_SBS_INFLUENCE_BINDING.
#ifndef PENUMBRA_SBS_PARAMS_BINDING
#define PENUMBRA_SBS_PARAMS_BINDING 1     // uniform block: PenumbraSbsParams (one slot per list block)
#endif
#ifndef PENUMBRA_SBS_INFLUENCE_BINDING
#define PENUMBRA_SBS_INFLUENCE_BINDING 2  // uniform block: PenumbraInfluenceParams
#endif
#ifndef PENUMBRA_SBS_COUNTS_BINDING
#define PENUMBRA_SBS_COUNTS_BINDING 0     // SSBOs from here on
#endif
#ifndef PENUMBRA_SBS_OFFSETS_BINDING
#define PENUMBRA_SBS_OFFSETS_BINDING 1
#endif
#ifndef PENUMBRA_SBS_POSITIONS_BINDING
#define PENUMBRA_SBS_POSITIONS_BINDING 2
#endif
#ifndef PENUMBRA_SBS_IDS_BINDING
#define PENUMBRA_SBS_IDS_BINDING 3
#endif
#ifndef PENUMBRA_SBS_MASKS_BINDING
#define PENUMBRA_SBS_MASKS_BINDING 4      // uint[sample_count * words]: blocked light samples
#endif
#ifndef PENUMBRA_SBS_WORK_BINDING
#define PENUMBRA_SBS_WORK_BINDING 5       // work counters
#endif
#ifndef PENUMBRA_SBS_LUT_BINDING
#define PENUMBRA_SBS_LUT_BINDING 6        // uvec4[]: the LUT (LightLutGenerator's table)
#endif
#ifndef PENUMBRA_SBS_SAMPLES_BINDING
#define PENUMBRA_SBS_SAMPLES_BINDING 7    // dvec4[K * R * N + R]: world light samples per (set, rotation
                                          // step), then (cos, sin) of the R steps (sampleBasedSoftSampleTable)
#endif
#ifndef PENUMBRA_SBS_SETS_BINDING
#define PENUMBRA_SBS_SETS_BINDING 8       // uint[sample_count]: selection word per view-sample id (bits 0-7
                                          // the set, bits 8-15 the rotation step)
#endif
#ifndef PENUMBRA_SBS_MARKS_BINDING
#define PENUMBRA_SBS_MARKS_BINDING 9      // uint[W * H]: penumbra texels (SoftSkips::silhouettes; light pass
                                          // and silhouette pass)
#endif
#ifndef PENUMBRA_SBS_NEAR_BINDING
#define PENUMBRA_SBS_NEAR_BINDING 10      // uint[sample_count]: the sample lies within the oracle's coplanar
                                          // reach of a kept closed triangle (SoftSkips::closed_casters)
#endif
#ifndef PENUMBRA_SBS_HEADER_BINDING
#define PENUMBRA_SBS_HEADER_BINDING 5     // the lists' header (block predicate pass only)
#endif
// Deferred pairs (SampleBasedSoftGpuOptions::deferred_pairs): the geometry stage stores each
// triangle's world vertices, the fragment stage appends (triangle, view sample) pairs, a compute
// pass does their work (light_pass.comp.glsl); fragments whose pairs do not fit append themselves
// to the fragments buffer instead, worked by the same pass a fragment per invocation.
#ifndef PENUMBRA_SBS_DEFERRAL_BINDING
#define PENUMBRA_SBS_DEFERRAL_BINDING 11  // uint[PENUMBRA_SBS_DEFERRAL_WORDS]: counters and dispatch arguments
#endif
#ifndef PENUMBRA_SBS_PAIRS_BINDING
#define PENUMBRA_SBS_PAIRS_BINDING 12     // uvec2[deferred_pairs]: PENUMBRA_SBS_PAIR_X / _Y
#endif
#ifndef PENUMBRA_SBS_TESTS_BINDING
#define PENUMBRA_SBS_TESTS_BINDING 14     // uvec4[deferred_tests]: (list slot, triangle slot, word, bits)
#endif
#ifndef PENUMBRA_SBS_TABLE_PAIRS_BINDING
#define PENUMBRA_SBS_TABLE_PAIRS_BINDING 15  // uint[deferred_pairs]: pairs (their index) for the tables pass
#endif
#ifndef PENUMBRA_SBS_TRIANGLES_BINDING
#define PENUMBRA_SBS_TRIANGLES_BINDING 13  // uint[PENUMBRA_SBS_TRIANGLE_WORDS * deferred_triangles]: per slot
#endif
#ifndef PENUMBRA_SBS_FRAGMENTS_BINDING
#define PENUMBRA_SBS_FRAGMENTS_BINDING 16  // uvec2[deferred_fragments]: (triangle slot, texel x | y << 16)
#endif
// The compute light pass's casters (SoftLightPass::Compute; caster_buffer.glsl).
#ifndef PENUMBRA_SBS_CASTER_POSITIONS_BINDING
#define PENUMBRA_SBS_CASTER_POSITIONS_BINDING 17  // float[]: CasterBuffer::positions
#endif
#ifndef PENUMBRA_SBS_CASTER_INDICES_BINDING
#define PENUMBRA_SBS_CASTER_INDICES_BINDING 18    // uint[]: CasterBuffer::indices
#endif
// Resolve.
#ifndef PENUMBRA_SBS_SLOTS_BINDING
#define PENUMBRA_SBS_SLOTS_BINDING 0
#endif
#ifndef PENUMBRA_SBS_TEXELS_BINDING
#define PENUMBRA_SBS_TEXELS_BINDING 1
#endif
#ifndef PENUMBRA_SBS_VISIBILITY_BINDING
#define PENUMBRA_SBS_VISIBILITY_BINDING 2  // float[sample_count]: visible fraction (resolve output)
#endif
// The resolve also reads offsets (PENUMBRA_SBS_RESOLVE_OFFSETS_BINDING) and masks, and counts into work.
#ifndef PENUMBRA_SBS_RESOLVE_OFFSETS_BINDING
#define PENUMBRA_SBS_RESOLVE_OFFSETS_BINDING 3
#endif

// Modes (params.config.x): penumbra::SoftMode.
#define PENUMBRA_SBS_MODE_EXACT 0u
#define PENUMBRA_SBS_MODE_LUT 1u
#define PENUMBRA_SBS_MODE_BRUTE 2u
// The same values for the preprocessor (no suffix): the light pass's PENUMBRA_SBS_MODE define.
#define PENUMBRA_SBS_MODE_EXACT_ID 0
#define PENUMBRA_SBS_MODE_LUT_ID 1
#define PENUMBRA_SBS_MODE_BRUTE_ID 2
// Mask words per view sample at most (N <= 1024 light samples per set).
#define PENUMBRA_SBS_MAX_WORDS 32u

// Visibility values the resolve writes for samples it could not evaluate (visible fraction
// otherwise, in [0, 1]).
#define PENUMBRA_SBS_VISIBILITY_NO_SAMPLE (-1.0)  // background (position w == 0)
#define PENUMBRA_SBS_VISIBILITY_UNTESTED (-2.0)   // outside the light frustum, non-finite, or past
                                                  // the list blocks walked (max_list_blocks)

// Work counters (words of the work buffer).
#define PENUMBRA_SBS_WORK_FRAGMENTS 0
#define PENUMBRA_SBS_WORK_PAIRS 1            // (view sample, caster) pairs evaluated
#define PENUMBRA_SBS_WORK_PAIRS_IGNORED 2    // coplanar rule for every light sample
#define PENUMBRA_SBS_WORK_PAIRS_UNPROVEN 3   // exact: every bit decided by the exact test
#define PENUMBRA_SBS_WORK_UNCERTAIN_BITS 4   // exact: pair bits the LUT did not vouch for
#define PENUMBRA_SBS_WORK_EXACT_TESTS 5      // per-(view sample, light sample) exact tests
#define PENUMBRA_SBS_WORK_OVERFLOW 6         // samples left untested past the last list block (resolve)
#define PENUMBRA_SBS_WORK_PLANES_UNPROVEN 7  // exact: planes whose rounding bound exceeded the budget
// Skips (penumbra::SoftSkips): the work each removed.
#define PENUMBRA_SBS_WORK_FRAGMENTS_SKIPPED 8  // fragments of empty list blocks that returned at once
#define PENUMBRA_SBS_WORK_TRIANGLES_CULLED 9   // closed casters' triangles facing away from the whole light
                                               // (counted in list block 0 only)
#define PENUMBRA_SBS_WORK_PAIRS_CUT 10         // pairs whose receiver and light lie on one side of the caster
#define PENUMBRA_SBS_WORK_PAIRS_HARD 11        // pairs outside every silhouette's region: one test from the centre
#define PENUMBRA_SBS_WORK_PAIRS_RECOVERED 12   // culled casters' pairs evaluated after all (near receivers)
#define PENUMBRA_SBS_WORK_PAIRS_FRONT 13       // pairs with the whole light in front of one (proven) plane: no table read
#define PENUMBRA_SBS_WORK_DEFERRED 14          // deferred pairs: (triangle, view sample) pairs the compute pass worked
#define PENUMBRA_SBS_WORK_FALLBACKS 15         // deferred pairs: draws redrawn by the fragment stage (overflow)
#define PENUMBRA_SBS_WORK_PAIRS_WEDGED 16      // pairs whose view sample lies beyond one of T's wedge planes
#define PENUMBRA_SBS_WORK_BAD_INDICES 17       // compute light pass: caster triangles naming a vertex past
                                               // their positions (cast nothing; counted once per frame)
#define PENUMBRA_SBS_WORK_CHUNKS 18            // compute light pass: runs of the deferred passes that had work
                                               // (the chunks a frame's pairs took; counted always)
#define PENUMBRA_SBS_WORK_WORDS 19

// The deferral buffer's words (PENUMBRA_SBS_DEFERRAL_BINDING).
#define PENUMBRA_SBS_DEFERRAL_PAIRS 0        // pairs appended since the last dispatch (may exceed the capacity)
#define PENUMBRA_SBS_DEFERRAL_TRIANGLES 1    // triangle slots taken since the last dispatch (may exceed theirs)
#define PENUMBRA_SBS_DEFERRAL_DISPATCHED 2   // pairs the compute pass reads (0 when the draws overflowed)
#define PENUMBRA_SBS_DEFERRAL_OVERFLOW 3     // set by a fragment whose triangle got no slot
#define PENUMBRA_SBS_DEFERRAL_ARGS 4         // 3 words: glDispatchComputeIndirect's group counts
#define PENUMBRA_SBS_DEFERRAL_FALLBACK 7     // the last draws overflowed: the fragment stage redraws them
#define PENUMBRA_SBS_DEFERRAL_PENDING 8      // PENUMBRA_SBS_WORK_WORDS counters of the deferring draws (to 27 at most)
#define PENUMBRA_SBS_DEFERRAL_TESTS 28       // exact-test words appended by the compute pass (may exceed the capacity)
#define PENUMBRA_SBS_DEFERRAL_TESTS_DISPATCHED 29  // words the exact-test pass reads
#define PENUMBRA_SBS_DEFERRAL_SAMPLES 30     // pairs handed to the tables pass (at most the pairs dispatched)
#define PENUMBRA_SBS_DEFERRAL_SAMPLES_DISPATCHED 31  // pairs the tables pass reads
#define PENUMBRA_SBS_DEFERRAL_TEST_ARGS 32   // 3 words: the exact-test pass's group counts
#define PENUMBRA_SBS_DEFERRAL_SAMPLE_ARGS 36  // 3 words: the tables pass's group counts
#define PENUMBRA_SBS_DEFERRAL_FRAGMENTS 39   // fragments appended to the fragments buffer (may exceed the capacity)
#define PENUMBRA_SBS_DEFERRAL_FRAGMENTS_DISPATCHED 40  // fragments the per-fragment pass reads
#define PENUMBRA_SBS_DEFERRAL_EMPTY 41       // empty pairs below the capacity (the one fragment that straddled it)
#define PENUMBRA_SBS_DEFERRAL_REGIONS 42   // coverage: region records appended (may exceed the capacity)
#define PENUMBRA_SBS_DEFERRAL_REGIONS_DISPATCHED 43  // coverage: region records the coverage pass reads
#define PENUMBRA_SBS_DEFERRAL_FRAGMENT_ARGS 44  // 3 words: the per-fragment pass's group counts
#define PENUMBRA_SBS_DEFERRAL_REGION_ARGS 48  // 3 words: the coverage pass's group counts
#define PENUMBRA_SBS_DEFERRAL_INLINE_ARGS 52  // 3 words: compute light pass, the coverage pass working its
                                              // regions' pairs itself (0 groups unless the pairs overflowed)
#define PENUMBRA_SBS_DEFERRAL_ITEMS_DISPATCHED 55  // coverage: (record, tile) work items the coverage pass reads
#define PENUMBRA_SBS_DEFERRAL_SETUP 56       // 2 words: the compute light pass's setup counts (culled triangles,
                                             // bad indices), kept whatever overflows
#define PENUMBRA_SBS_DEFERRAL_SETUP_ARGS 58  // 3 words: the compute light pass's setup dispatch (x: triangles,
                                             // y: the list blocks of this dispatch that some list reaches)
#define PENUMBRA_SBS_DEFERRAL_ROUND_ARGS 61  // 3 words: compute light pass, (1, 1, 1) when the deferred passes have
                                             // work since their last run, else (0, 1, 1): their one-invocation programs' group counts
#define PENUMBRA_SBS_DEFERRAL_SPLIT 64      // compute light pass: the windows the last overflowed run is split into
                                             // (0: none; run k of them works the records r with r % SPLIT == k)
#define PENUMBRA_SBS_DEFERRAL_WORDS 68
#define PENUMBRA_SBS_DEFERRAL_GROUP 256      // light_pass.comp.glsl's workgroup size
#define PENUMBRA_SBS_COVERAGE_GROUP 64      // light_pass_coverage.comp.glsl's workgroup size
#define PENUMBRA_SBS_SETUP_GROUP 64         // light_pass_setup.comp.glsl's workgroup size
// The coverage pass's inline program: workgroups of at most 64 invocations, one per texel of a
// (record, tile) item, PENUMBRA_SBS_INLINE_PARTS(rows * columns) of them per item.
#define PENUMBRA_SBS_INLINE_GROUP(texels) ((texels) < 64u ? (texels) : 64u)
#define PENUMBRA_SBS_INLINE_PARTS(texels) \
    (((texels) + PENUMBRA_SBS_INLINE_GROUP(texels) - 1u) / PENUMBRA_SBS_INLINE_GROUP(texels))
#define PENUMBRA_SBS_COVERAGE_SCAN_GROUP 256  // the coverage pass's scan of first items (one workgroup)
// A region record (coverage, after the triangle slots in the triangles buffer): the triangle's
// slot, the polygon's vertex count n, then n vec2 (grid pixels) as float bits.
#define PENUMBRA_SBS_REGION_WORDS(k) (2u + 2u * uint(PENUMBRA_INFLUENCE_MAX_VERTICES(k)))
#define PENUMBRA_SBS_NO_TRIANGLE 0xFFFFFFFFu // no slot: the draws overflowed
#define PENUMBRA_SBS_TRIANGLE_WORDS 28u      // a slot: 9 float bits (world vertices), list block | flags << 16,
                                             // with SoftSkips::wedges its 4 planes and 2 margins (wedges.glsl)
// A deferred pair (pairs buffer, PENUMBRA_SBS_PAIRS_BINDING): one per (triangle slot, view sample of
// the fragment's list block), the sample as its index in the block: x = slot | (index & 0xFF) << 24,
// y = texel x | texel y << 13 | (index >> 8) << 26 (slots < 2^24, grid sides <= 8192, list blocks
// <= 4096 samples: the options' limits).
#define PENUMBRA_SBS_PAIR_X(slot, index) ((slot) | ((index) & 0xFFu) << 24u)
#define PENUMBRA_SBS_PAIR_Y(x, y, index) ((x) | (y) << 13u | ((index) >> 8u) << 26u)
#define PENUMBRA_SBS_PAIR_EMPTY 0xFFFFFFFFu  // y of an empty pair (index bits 63 << 8: no list block has it)

// Skip flags (params.reserved.y): penumbra::SoftSkips, and the class of the draw.
#define PENUMBRA_SBS_FLAG_SKIP_EMPTY 1u      // empty list blocks return before the caster's setup
#define PENUMBRA_SBS_FLAG_CULL_CLOSED 2u     // this draw's casters are closed: cull triangles the whole
                                             // light is strictly behind
#define PENUMBRA_SBS_FLAG_PLANE_CUT 4u       // skip pairs with p and the light on one side of T's plane
#define PENUMBRA_SBS_FLAG_SILHOUETTES 8u     // texels no potential silhouette's region marked: one hard test
#define PENUMBRA_SBS_FLAG_CULLED_PASS 16u    // the second pass over closed casters: only the culled triangles,
                                             // only for samples flagged near (with PENUMBRA_SBS_FLAG_CULL_CLOSED)
#define PENUMBRA_SBS_FLAG_COMPLEMENT 32u     // count_work's draw of the fragments the occupancy stencil
                                             // culled (empty blocks): the geometry stage counts no culled triangle

#ifdef __cplusplus
namespace penumbra::shared {  // C++: include penumbra/light_lut.hpp first (PenumbraLutParams)
#else
#include "penumbra/light_lut/light_lut_shared.h"
#endif

// std140 == std430: the dvec4 members first (32-aligned), then uvec4s, then the LUT's block.
// 7 dvec4 (224) + 4 uvec4 (64) + PenumbraLutParams (48) = 336 bytes.
struct PenumbraSbsParams {
    dvec4 center;       // xyz: LightFrame::center (world), w: the oracle's scene extent E capping
                        // |s - p|_inf in its tolerance scale (> 0; +inf = uncapped)
    dvec4 rotation[3];  // LightFrame::rotation columns (local x, y, z), w: 0
    dvec4 scale;        // xyz: LightFrame::scale, w: the smallest semi-axis
    dvec4 bounds;       // x: light reach (max semi-axis * sqrt 3), y: |centre| + reach, z: plane budget
                        // (normalised units), w: the LUT's margin in world units (budget * min scale)
    dvec4 epsilon;      // x: coplanar epsilon, y: tie epsilon, z: max of both, w: radius about the
                        // centre holding every light sample (SoftSkips::wedges; the pipeline sets
                        // sampleBasedSoftSampleReach, else the light's bound, x of bounds)
    uvec4 grid;         // x = W, y = H, z = list block (samples per fragment per pass), w = block index
    uvec4 config;       // x = mode, y = N (samples per set), z = K (sets), w = words per view sample
    uvec4 counts;       // x = sample count, y = samples per list walked (max_list_blocks * list block),
                        // z = tables per set, w = 1 when a per-sample set buffer is bound
    uvec4 reserved;     // x = R (rotation steps about local z; 1 = none), y = PENUMBRA_SBS_FLAG_* bits,
                        // z = float bits of SoftSkips::wedges' margin factor (detail::soft::wedgeMu2)
    PenumbraLutParams lut;
};

#ifdef __cplusplus
}  // namespace penumbra::shared
#endif

#endif
