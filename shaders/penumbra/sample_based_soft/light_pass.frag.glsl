// penumbra — sample-based soft shadows, light pass, fragment stage (sintorn2008 §4, Fig. 6). One
// fragment per (caster triangle, light texel its influence region covers): the pair's work
// (light_pass_work.glsl: walk one block of the texel's list of view samples, OR the light samples
// the triangle blocks into each sample's mask). No colour output; bind a W x H framebuffer with
// no attachments.
// With PENUMBRA_SBS_DEFERRED (SampleBasedSoftGpuOptions::deferred_pairs) a fragment appends
// (triangle slot, view sample) pairs to the pairs buffer instead, one per sample of its list block
// that no wedge plane of the triangle rejects (SoftSkips::wedges: PENUMBRA_SBS_WEDGES, wedges.glsl)
// (light_pass.geom.glsl stored the triangle's vertices in the slot), or, past that buffer's
// capacity, (triangle slot, texel) to the fragments buffer; the compute pass light_pass.comp.glsl
// does the same work after the draws. This program holds no pair work at all (llvmpipe runs a
// shader's every instruction for its masked-off lanes too: an unused fallback here cost more than
// the work). When the draws overflow the fragments buffer or the triangle slots, the pipeline draws them again with the
// program without PENUMBRA_SBS_DEFERRED (decided on the GPU) and the compute pass does nothing;
// this program's counters wait in the deferral buffer until that is decided
// (light_pass_args.comp.glsl). Either way every pair's work is the same function on the same
// inputs: the same bits and counters.
// Defines: light_pass_work.glsl's, PENUMBRA_SBS_DEFERRED.
// penumbra-permutation: PENUMBRA_SBS_COUNT_WORK=1
// penumbra-permutation: PENUMBRA_SBS_COUNT_WORK=0
// penumbra-permutation: PENUMBRA_SBS_MODE=1
// penumbra-permutation: PENUMBRA_SBS_MODE=1 PENUMBRA_SBS_SILHOUETTES=1
// penumbra-permutation: PENUMBRA_SBS_MODE=2 PENUMBRA_SBS_SILHOUETTES=1 PENUMBRA_SBS_CLOSED_CASTERS=1
// penumbra-permutation: PENUMBRA_SBS_DEFERRED=1
// penumbra-permutation: PENUMBRA_SBS_DEFERRED=1 PENUMBRA_SBS_MODE=1 PENUMBRA_SBS_COUNT_WORK=0
// penumbra-permutation: PENUMBRA_SBS_DEFERRED=1 PENUMBRA_SBS_WEDGES=1
// penumbra-permutation: PENUMBRA_SBS_WEDGES=1
#include "penumbra/sample_based_soft/light_pass_work.glsl"

#ifndef PENUMBRA_SBS_DEFERRED
#define PENUMBRA_SBS_DEFERRED 0
#endif
#if PENUMBRA_SBS_DEFERRED
layout(std430, binding = PENUMBRA_SBS_DEFERRAL_BINDING) buffer PenumbraSbsDeferral { uint penumbraSbsDeferral[]; };
layout(std430, binding = PENUMBRA_SBS_PAIRS_BINDING) writeonly buffer PenumbraSbsPairs { uvec2 penumbraSbsPairs[]; };
layout(std430, binding = PENUMBRA_SBS_FRAGMENTS_BINDING) writeonly buffer PenumbraSbsFragments { uvec2 penumbraSbsFragments[]; };
// Counters wait in the deferral buffer (kept only when the draws did not overflow).
#define PENUMBRA_SBS_COUNT(index) atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_PENDING + (index)], 1u)
#include "penumbra/sample_based_soft/deferral_append.glsl"
#else
#define PENUMBRA_SBS_COUNT(index) atomicAdd(penumbraSbsWork[index], 1u)
#endif

// SoftSkips::empty_blocks: the pipeline's occupancy stencil (occupancy.frag.glsl) culls empty list
// blocks' fragments before they are shaded, which needs the test before the shader's stores.
layout(early_fragment_tests) in;

#if !PENUMBRA_SBS_DEFERRED
layout(location = 0) flat in vec3 penumbraSbsVertex0;
layout(location = 1) flat in vec3 penumbraSbsVertex1;
layout(location = 2) flat in vec3 penumbraSbsVertex2;
#endif
layout(location = 3) flat in uint penumbraSbsTriangle;  // deferred pairs: the triangle's slot, or PENUMBRA_SBS_NO_TRIANGLE
#if PENUMBRA_SBS_WEDGES
layout(location = 4) flat in vec4 penumbraSbsWedge[4];  // SoftSkips::wedges (wedges.glsl)
layout(location = 8) flat in vec2 penumbraSbsWedgeMargin;
#endif

void main() {
    const PenumbraSbsParams P = penumbraSbsParams;
    const uvec2 texel = uvec2(gl_FragCoord.xy);
    const uvec2 range = penumbraSampleListsBlock(ivec2(texel), P.grid.w, P.grid.z);
#if PENUMBRA_SBS_CLOSED_CASTERS
    // The second pass over closed casters: texels without a flagged sample have nothing to do.
    if ((P.reserved.y & PENUMBRA_SBS_FLAG_CULLED_PASS) != 0u &&
        penumbraSbsNear[P.counts.x + texel.y * P.grid.x + texel.x] == 0u) {
#if PENUMBRA_SBS_COUNT_WORK
        PENUMBRA_SBS_COUNT(PENUMBRA_SBS_WORK_FRAGMENTS);
        PENUMBRA_SBS_COUNT(PENUMBRA_SBS_WORK_FRAGMENTS_SKIPPED);
#endif
        return;
    }
#endif
    if (range.y == 0u && (P.reserved.y & PENUMBRA_SBS_FLAG_SKIP_EMPTY) != 0u) {
        // SoftSkips::empty_blocks: an empty list block (an empty texel, or past its list's end) has
        // nothing to test. The pipeline's occupancy stencil culls these fragments before shading
        // (blocks 0..254); those that arrive (count_work's complement draw, later blocks) return
        // before the caster's per-fragment setup. Off: the same setup as any fragment, then an
        // empty walk.
#if PENUMBRA_SBS_COUNT_WORK
        PENUMBRA_SBS_COUNT(PENUMBRA_SBS_WORK_FRAGMENTS);
        PENUMBRA_SBS_COUNT(PENUMBRA_SBS_WORK_FRAGMENTS_SKIPPED);
#endif
        return;
    }
#if PENUMBRA_SBS_DEFERRED
    if (range.y == 0u) {
        // An empty list block with SoftSkips::empty_blocks off: the pair's work would be an empty
        // walk, which counts the fragment and nothing else.
#if PENUMBRA_SBS_COUNT_WORK
        PENUMBRA_SBS_COUNT(PENUMBRA_SBS_WORK_FRAGMENTS);
#endif
        return;
    }
    if (penumbraSbsTriangle == PENUMBRA_SBS_NO_TRIANGLE) {
        penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_OVERFLOW] = 1u;  // the triangle found no slot
        return;
    }
    // One pair per view sample of the block (deferral_append.glsl): the compute pass's lanes each
    // walk one sample (a group of lanes walking whole blocks would take as long as its longest
    // block).
#if PENUMBRA_SBS_WEDGES
    penumbraSbsAppendBlock(texel, range, penumbraSbsTriangle, PenumbraSbsWedges(penumbraSbsWedge, penumbraSbsWedgeMargin));
#else
    penumbraSbsAppendBlock(texel, range, penumbraSbsTriangle, penumbraSbsNoWedges());
#endif
#else
#if PENUMBRA_SBS_WEDGES
    const PenumbraSbsWedges wedges = PenumbraSbsWedges(penumbraSbsWedge, penumbraSbsWedgeMargin);
#else
    const PenumbraSbsWedges wedges = penumbraSbsNoWedges();
#endif
    penumbraSbsTexelWork(P, texel, range, dvec3(penumbraSbsVertex0), dvec3(penumbraSbsVertex1), dvec3(penumbraSbsVertex2), wedges);
#endif
}
