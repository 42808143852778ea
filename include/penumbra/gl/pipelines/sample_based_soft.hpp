// penumbra — sample-based soft shadows (sintorn2008 §4, Fig. 5, 6) on the GPU: view samples →
// lists → light pass rasterizing each caster's influence region → for every view sample of a
// covered texel the LUT masks of the 3 edge planes + the supporting plane (AND), OR-ed into the
// sample's N-bit mask → resolve (visible fraction). Composed from the blocks' public APIs:
// penumbra/gl/sample_lists.hpp (lists), penumbra/influence_region.hpp (the hull, §4.1),
// penumbra/light_lut.hpp + lookup.glsl (masks, §4.2), the hard pipeline's exact segment test
// (blocker_test.glsl) for the bits the certified LUT cannot vouch for, and its caster hook and
// list-block predicate. Options, pure setup and the CPU twin of the per-pair work:
// penumbra/pipelines/sample_based_soft.hpp (no GL).
//
// Integration summary
//   needs:    GL 4.5 with fp64 in shaders (the planes and the exact test are fp64 in every mode),
//             geometry shaders, 8 fragment-stage storage blocks plus one each for count_work,
//             skips.closed_casters and skips.silhouettes, and with deferred_pairs (the default)
//             2-3 in the geometry stage and as many plus 3 in compute (checked at construction);
//             shaders penumbra/sample_based_soft/*, penumbra/alias_free_hard/{caster_position,
//             blocker_test,degenerate}.glsl and blocks.vert.glsl, penumbra/influence_region/*,
//             penumbra/light_lut/lookup.glsl, penumbra/sample_lists/*.
//   setup:    SampleBasedSoftShadows(options, sets, lut, influence, view_projection, library,
//             bindings): `sets` the
//             light samples (K sets of N; uploaded as fp64 world positions), `lut` the LUT's setup
//             (certified for Exact; null allowed for Brute), `influence` an influenceRegionSetup for
//             the same light and the options' grid, made with `view_projection` (a perspective
//             projection from the light centre, lightViewProjectionForBounds): the light grid the
//             lists are built with (no §4.3 refit: the hull needs the grid on the host) and its far
//             plane must lie beyond every receiver. reserve(max samples); validate(...) checks
//             the integrator's ranges once (GL queries, throws).
//   input:    view samples as ranges of vec4 world positions (w == 0 = none) and vec4 normals
//             (SampleBufferInput; normals unused: every sample is tested, light-back-facing ones
//             included, so the result is the oracle's), or the engine's depth buffer + inverse
//             view-projection (SampleDepthInput: positions reconstructed on the GPU; the lists'
//             list_positions / list_ids hold the float positions the exact test used); the LUT table (LightLutGenerator's, or
//             generateLightLut uploaded) as a BufferRange; optionally a selection word per sample
//             id naming its light-sample set and rotation step (sampleBasedSoftSelection per
//             pixel; empty = set 0, unrotated; options.rotations steps); a callback that
//             draws every caster of the CasterClass it is given (positions through
//             penumbraAfhCasterPosition(), attribute 0 by default) while the pipeline's light-pass
//             program is bound: Closed = watertight outward-oriented meshes (SoftSkips::
//             closed_casters culls their triangles that face away from the whole light), Open =
//             the rest. options.skips: the work skips (SoftSkips), none of which changes a bit of
//             Exact or Brute. options.deferred_pairs: the light pass's pair work in a compute pass
//             instead of its fragment stage (same bits and counters). options.coverage_texels
//             (with deferred_pairs): small influence regions visited by a compute pass instead of
//             drawn (Exact and Brute: the same bits; the counters grow by the boundary texels it
//             adds, ~0.3 % of the fragments).
//   produces: per view-sample id `words = ceil(N / 32)` mask words (bit s of word id * words +
//             s / 32: light sample s of its set blocked) in masks() or your range, and the visible
//             fraction 1 - popcount / N as a float per id (PENUMBRA_SBS_VISIBILITY_NO_SAMPLE /
//             _UNTESTED otherwise) in visibility() or your range; on request (readFrame(), which
//             waits) list statistics, passes, work counters and (options.timings) per-stage GPU
//             times; readMasks() / readVisibility().
//   per frame: run() — (1) lists (count, scan, scatter; the influence setup's view-projection)
//             + statistics, (2) a predicate pass: one point per list block inside an occlusion
//             query, surviving when the longest list needs that block, (2b) with
//             skips.silhouettes the silhouette pass (your DrawAdjacency twice), (2c) with
//             skips.empty_blocks the occupancy pass: a full-screen triangle per block (under the
//             same conditional render) increments a W x H GL_STENCIL_INDEX8 stencil where the
//             texel's block holds samples, (3) the light pass:
//             for each block b < max_list_blocks under glBeginConditionalRender(query b), every
//             caster drawn (your callback with Closed, then Open) into the pipeline's W x H
//             framebuffer (the stencil its only attachment; with skips.empty_blocks the stencil
//             test GL_LESS b and early fragment tests cull empty blocks' fragments before they are
//             shaded, blocks 0..254; count_work draws the culled ones once more, GL_GEQUAL b, to
//             count them); the geometry stage culls (skips) and emits the influence region, each
//             fragment walks its texel's list block (light_pass_work.glsl) or, with deferred_pairs,
//             appends (triangle slot, texel) for (3b) the compute pass (with coverage_texels, first
//             a compute pass sets one occupancy bit per non-empty texel, the geometry stage hands
//             regions whose box spans at most coverage_texels texels to the coverage pass as
//             records instead of emitting them, and after the draws the coverage pass
//             (light_pass_coverage.comp.glsl) visits their rows' non-empty texels and appends
//             their pairs as the fragments would): a one-invocation dispatch
//             turns the count into group counts, glDispatchComputeIndirect works every appended pair
//             (light_pass.comp.glsl), the same way the tables pass its samples that need the LUT's
//             tables (light_pass_tables.comp.glsl) and the exact-test pass the pending words of
//             both (light_pass_tests.comp.glsl); when the draws overflowed the pairs buffer or the triangle
//             slots, nothing is dispatched and a second set of list-block predicates (one point
//             per block, true only then) draws the same blocks again with the fragment-stage
//             program; with skips.closed_casters then once more per block with Closed (the culled
//             triangles, for the receivers that need them; with skips.empty_blocks a full-screen
//             triangle first zeroes the stencil on the texels without such a receiver, and unless
//             count_work one full-screen triangle per block inside an occlusion query finds whether
//             the block holds one at all: the blocks that hold none are not drawn) and (3b)
//             again, (4) resolve. Nothing
//             is read back, queried, allocated or thrown: misuse returns a Status.
//   compute:  options.light_pass = SoftLightPass::Compute: run() takes the casters as CasterBuffer
//             ranges instead of a callback, and (2), (2c) and (3)'s draws become compute passes: for
//             each list block b and class, one dispatch per range (light_pass_setup.comp.glsl, one
//             invocation per triangle: blocks no list reaches return at once) stores every
//             triangle's slot and region record, then the coverage pass and (3b) as above; the host
//             runs (3b) whenever the triangles dispatched since the last run could fill the slots
//             (so none overflows); when the pairs and fragments overflow, the coverage pass's
//             program that works the pairs itself runs instead of the redraw (group counts decided
//             on the GPU). No draw, query, stencil or framebuffer call; the GL state it changes is
//             the program, the buffer bindings above plus SbsBindings::caster_positions /
//             caster_indices, and GL_DISPATCH_INDIRECT_BUFFER.
//
// GL state: changes without restoring the current program, the draw framebuffer binding (the
// pipeline's own), the viewport, GL_DEPTH_TEST (off), GL_CULL_FACE (off), GL_RASTERIZER_DISCARD
// (off), GL_STENCIL_TEST (off at the end), the stencil function, operations and write mask (0
// at the end) with skips.empty_blocks, the rasterizer state of gl::setPassRasterState (scissor test off, polygon fill, clip
// distances off, clip control lower-left / -1..1, ...: the engine's leftovers cannot clip the
// passes), the vertex-array binding (its own empty VAO during the predicate and occupancy passes; then whatever
// your callback binds), the uniform-buffer bindings and SSBO bindings of SbsBindings, the
// GL_DISPATCH_INDIRECT_BUFFER binding (the deferral buffer, with deferred_pairs), and
// whatever the sample-list builder and scanner bind. Your callback must leave the light pass's
// SSBO bindings alone. Ends with GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT.
#ifndef PENUMBRA_GL_PIPELINES_SAMPLE_BASED_SOFT_HPP
#define PENUMBRA_GL_PIPELINES_SAMPLE_BASED_SOFT_HPP

#include "penumbra/buffer_range.hpp"
#include "penumbra/gl/objects.hpp"
#include "penumbra/gl/sample_lists.hpp"
#include "penumbra/gl/shader.hpp"
#include "penumbra/gl/validate.hpp"
#include "penumbra/influence_region.hpp"
#include "penumbra/pipelines/sample_based_soft.hpp"

#include <algorithm>
#include <cstring>
#include <functional>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

namespace penumbra {

/// Binding points; value-initialised = sample_based_soft_shared.h.
struct SbsBindings {
    uint32_t params = PENUMBRA_SBS_PARAMS_BINDING;        ///< uniform block
    uint32_t influence = PENUMBRA_SBS_INFLUENCE_BINDING;  ///< uniform block
    uint32_t counts = PENUMBRA_SBS_COUNTS_BINDING;        ///< SSBOs from here on (light pass)
    uint32_t offsets = PENUMBRA_SBS_OFFSETS_BINDING;
    uint32_t positions = PENUMBRA_SBS_POSITIONS_BINDING;
    uint32_t ids = PENUMBRA_SBS_IDS_BINDING;
    uint32_t masks = PENUMBRA_SBS_MASKS_BINDING;
    uint32_t work = PENUMBRA_SBS_WORK_BINDING;
    uint32_t lut = PENUMBRA_SBS_LUT_BINDING;
    uint32_t samples = PENUMBRA_SBS_SAMPLES_BINDING;
    uint32_t sets = PENUMBRA_SBS_SETS_BINDING;
    uint32_t header = PENUMBRA_SBS_HEADER_BINDING;  ///< predicate pass
    uint32_t slots = PENUMBRA_SBS_SLOTS_BINDING;    ///< resolve
    uint32_t texels = PENUMBRA_SBS_TEXELS_BINDING;
    uint32_t visibility = PENUMBRA_SBS_VISIBILITY_BINDING;
    uint32_t resolve_offsets = PENUMBRA_SBS_RESOLVE_OFFSETS_BINDING;
    uint32_t marks = PENUMBRA_SBS_MARKS_BINDING;  ///< SoftSkips::silhouettes
    uint32_t near_samples = PENUMBRA_SBS_NEAR_BINDING;  ///< SoftSkips::closed_casters
    uint32_t deferral = PENUMBRA_SBS_DEFERRAL_BINDING;    ///< deferred pairs: counters and dispatch arguments
    uint32_t pairs = PENUMBRA_SBS_PAIRS_BINDING;          ///< deferred pairs: (triangle slot, view sample)
    uint32_t triangles = PENUMBRA_SBS_TRIANGLES_BINDING;  ///< deferred pairs: triangle slots
    uint32_t tests = PENUMBRA_SBS_TESTS_BINDING;          ///< deferred pairs: pending exact-test words
    uint32_t table_pairs = PENUMBRA_SBS_TABLE_PAIRS_BINDING;  ///< deferred pairs: pairs for the tables pass
    uint32_t fragments = PENUMBRA_SBS_FRAGMENTS_BINDING;      ///< deferred pairs: fragments past the pairs buffer
    uint32_t caster_positions = PENUMBRA_SBS_CASTER_POSITIONS_BINDING;  ///< SoftLightPass::Compute: CasterBuffer::positions
    uint32_t caster_indices = PENUMBRA_SBS_CASTER_INDICES_BINDING;      ///< SoftLightPass::Compute: CasterBuffer::indices
    SampleListsBindings lists{};  ///< the sample-list builder's
};

/// Per-frame ranges of run(); empty = the executor's own buffers (sets: set 0 for every sample).
struct SbsFrameBuffers {
    BufferRange sets;        ///< uint[sample_count]: selection word per view-sample id (sampleBasedSoftSelection)
    BufferRange masks;       ///< uint[sample_count * words]: output
    BufferRange visibility;  ///< float[sample_count]: output
};

/// What readFrame() reports about the last run.
struct SampleBasedSoftFrame {
    SampleListStatistics statistics;
    uint32_t passes = 0;  ///< list blocks the light pass needed (<= max_list_blocks)
    // Work counters (count_work; overflow always).
    uint64_t fragments = 0, pairs = 0, pairs_ignored = 0, pairs_unproven = 0, uncertain_bits = 0, exact_tests = 0,
             planes_unproven = 0, overflow = 0;
    /// What the skips removed (SoftSkips; count_work): fragments of empty list blocks (culled by
    /// the occupancy stencil before shading; count_work draws them once more to count them), closed
    /// casters' triangles culled (per frame, not per block), pairs cut by T's plane.
    uint64_t fragments_skipped = 0, triangles_culled = 0, pairs_cut = 0;
    /// SoftSkips::silhouettes: pairs outside every silhouette's region (one exact test each).
    uint64_t pairs_hard = 0;
    /// SoftSkips::closed_casters: culled triangles' pairs evaluated after all in the second pass, the
    /// sample lying within the oracle's coplanar reach of a kept closed triangle.
    uint64_t pairs_recovered = 0;
    /// Pairs decided at once because the whole light lies in front of one (in Exact: proven) plane
    /// of the pair: no LUT table read (Lut and Exact).
    uint64_t pairs_front = 0;
    /// SoftSkips::wedges: (triangle, view sample) pairs skipped by the triangle's wedge planes, in no
    /// other counter (with deferred pairs never appended; nor counted in pairs_recovered).
    uint64_t pairs_wedged = 0;
    /// Deferred pairs (options.deferred_pairs): (caster triangle, view sample) pairs the compute pass
    /// worked: when no draw overflowed, one per view sample in the list block of every fragment but
    /// those skipped (with SoftSkips::empty_blocks off, empty blocks' fragments append none) and
    /// the view samples SoftSkips::wedges rejects. They
    /// include the pairs that end before `pairs` counts them (cut, not flagged near).
    uint64_t pairs_deferred = 0;
    /// Deferred pairs: passes (the first, the closed casters' second) that overflowed the pairs
    /// buffer or the triangle slots and were drawn again with the fragment-stage program.
    uint64_t deferral_fallbacks = 0;
    /// SoftLightPass::Compute: caster triangles naming a vertex past their CasterBuffer's positions
    /// (they cast nothing: the masks miss their shadows; count_work).
    uint64_t caster_indices_out_of_range = 0;
    /// SoftLightPass::Compute: runs of the deferred passes that had work, i.e. the chunks the frame's
    /// triangles and pairs were split into to fit the slots and buffers reserved (decided on the
    /// GPU; counted with or without count_work). 0 with the raster light pass.
    uint64_t chunks = 0;
    /// GPU nanoseconds per stage (options.timings; 0 otherwise): lists (count, scan, scatter,
    /// statistics), light pass (predicate + every list block), resolve.
    uint64_t lists_ns = 0, light_pass_ns = 0, resolve_ns = 0;
};

class SampleBasedSoftShadows {
public:
    /// Draws every caster of one class (CasterClass::Closed: watertight, outward-oriented meshes,
    /// culled per SoftSkips::closed_casters; Open: the rest), as the hard pipeline's callback.
    using DrawCasters = std::function<void(CasterClass)>;
    /// SoftSkips::silhouettes: draws every caster (both classes) as GL_TRIANGLES_ADJACENCY
    /// (penumbra::triangleAdjacency's indices, positions as for DrawCasters) with the bound program.
    using DrawAdjacency = std::function<void()>;

    SampleBasedSoftShadows(const SampleBasedSoftGpuOptions& options, const LightSampleSets& sets, const LightLutSetup* lut,
                           const InfluenceRegionSetup& influence, const glm::mat4& view_projection,
                           const ShaderLibrary& library = ShaderLibrary::embedded(),
                           const SbsBindings& bindings = {})
        : options_(options), bindings_(bindings), builder_(library, {}, bindings.lists) {
        validateSampleBasedSoftGpuOptions(options_);
        PENUMBRA_CHECK(uint32_t(influence.width()) == options_.grid_width && uint32_t(influence.height()) == options_.grid_height,
                       "penumbra::SampleBasedSoftShadows: the influence setup's grid ", influence.width(), " x ",
                       influence.height(), " differs from the options' ", options_.grid_width, " x ", options_.grid_height);
        n_ = sets.count();
        k_ = sets.sets();
        words_ = (n_ + 31) / 32;
        if (lut) lut_ = *lut;
        has_lut_ = lut != nullptr;
        sets_ = sets;
        influence_ = influence;
        // Checks the LUT against the sets and the mode (throws).
        (void)sampleBasedSoftParams(options_, sets_, lut, 0, 0, false);
        const bool compute = options_.light_pass == SoftLightPass::Compute;
        const GLint fragment_blocks = compute ? 0 : gl::getInteger(GL_MAX_FRAGMENT_SHADER_STORAGE_BLOCKS);
        const GLint needed = (options_.count_work ? 9 : 8) + (options_.skips.silhouettes ? 1 : 0) +
                             (options_.skips.closed_casters ? 1 : 0);
        PENUMBRA_CHECK(compute || fragment_blocks >= needed, "penumbra::SampleBasedSoftShadows: GL_MAX_FRAGMENT_SHADER_STORAGE_BLOCKS = ",
                       fragment_blocks, ", the light pass needs ", needed,
                       " (8, plus one each for count_work, skips.closed_casters and skips.silhouettes)");
        if (options_.count_work && !compute) {
            const GLint geometry_blocks = gl::getInteger(GL_MAX_GEOMETRY_SHADER_STORAGE_BLOCKS);
            PENUMBRA_CHECK(geometry_blocks >= 1, "penumbra::SampleBasedSoftShadows: GL_MAX_GEOMETRY_SHADER_STORAGE_BLOCKS = ",
                           geometry_blocks, ": count_work needs 1 (the culled-triangle counter); set count_work = false");
        }
        ShaderDefines defines = influence.defines;
        defines.push_back({"PENUMBRA_SBS_COUNT_WORK", options_.count_work ? "1" : "0"});
        defines.push_back({"PENUMBRA_SBS_MODE", std::to_string(static_cast<uint32_t>(options_.mode))});
        defines.push_back({"PENUMBRA_SBS_SILHOUETTES", options_.skips.silhouettes ? "1" : "0"});
        defines.push_back({"PENUMBRA_SBS_CLOSED_CASTERS", options_.skips.closed_casters ? "1" : "0"});
        defines.push_back({"PENUMBRA_SBS_WEDGES", options_.skips.wedges ? "1" : "0"});
        const SbsBindings& b = bindings_;
        const std::pair<const char*, uint32_t> binding_defines[] = {
            {"PENUMBRA_SBS_PARAMS_BINDING", b.params},       {"PENUMBRA_SBS_INFLUENCE_BINDING", b.influence},
            {"PENUMBRA_SBS_COUNTS_BINDING", b.counts},       {"PENUMBRA_SBS_OFFSETS_BINDING", b.offsets},
            {"PENUMBRA_SBS_POSITIONS_BINDING", b.positions}, {"PENUMBRA_SBS_IDS_BINDING", b.ids},
            {"PENUMBRA_SBS_MASKS_BINDING", b.masks},         {"PENUMBRA_SBS_WORK_BINDING", b.work},
            {"PENUMBRA_SBS_LUT_BINDING", b.lut},             {"PENUMBRA_SBS_SAMPLES_BINDING", b.samples},
            {"PENUMBRA_SBS_SETS_BINDING", b.sets},           {"PENUMBRA_SBS_HEADER_BINDING", b.header},
            {"PENUMBRA_SBS_SLOTS_BINDING", b.slots},         {"PENUMBRA_SBS_TEXELS_BINDING", b.texels},
            {"PENUMBRA_SBS_VISIBILITY_BINDING", b.visibility}, {"PENUMBRA_SBS_RESOLVE_OFFSETS_BINDING", b.resolve_offsets},
            {"PENUMBRA_SBS_MARKS_BINDING", b.marks},         {"PENUMBRA_SBS_NEAR_BINDING", b.near_samples},
            {"PENUMBRA_SBS_DEFERRAL_BINDING", b.deferral},   {"PENUMBRA_SBS_PAIRS_BINDING", b.pairs},
            {"PENUMBRA_SBS_TRIANGLES_BINDING", b.triangles}, {"PENUMBRA_SBS_TESTS_BINDING", b.tests},
            {"PENUMBRA_SBS_TABLE_PAIRS_BINDING", b.table_pairs}, {"PENUMBRA_SBS_FRAGMENTS_BINDING", b.fragments},
            {"PENUMBRA_SBS_CASTER_POSITIONS_BINDING", b.caster_positions}, {"PENUMBRA_SBS_CASTER_INDICES_BINDING", b.caster_indices}};
        for (const auto& d : binding_defines) defines.push_back({d.first, std::to_string(d.second)});
        const bool deferred = options_.deferred_pairs > 0;
        // Every binding a program uses below the driver's limit (GL's minimum is 8 storage
        // bindings; the defaults reach 16 with deferred pairs, the six entries before the last
        // two, and 18 with the compute light pass's casters, the last two).
        const GLint max_storage = gl::getInteger(GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS);
        const GLint max_uniform = gl::getInteger(GL_MAX_UNIFORM_BUFFER_BINDINGS);
        const size_t binding_count = std::size(binding_defines) - (compute ? 0 : 2) - (deferred ? 0 : 6);
        for (size_t i = 0; i < binding_count; ++i) {
            const bool uniform = i < 2;  // params, influence
            const GLint limit = uniform ? max_uniform : max_storage;
            PENUMBRA_CHECK(binding_defines[i].second < static_cast<uint32_t>(std::max<GLint>(limit, 0)),
                           "penumbra::SampleBasedSoftShadows: ", binding_defines[i].first, " = ", binding_defines[i].second,
                           " is not below ", uniform ? "GL_MAX_UNIFORM_BUFFER_BINDINGS = " : "GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS = ",
                           limit, " (choose lower SbsBindings", deferred ? ", or set deferred_pairs = 0)" : ")");
        }
        const Capacities cap = capacities(options_, influence.sides());
        const bool coverage = cap.regions > 0;
        const uint32_t slots = cap.slots, regions = cap.regions, region_words = cap.region_words;
        const uint32_t occupancy_row = (options_.grid_width + 31) / 32;
        const uint64_t occupancy_words = cap.occupancy_words;
        slots_ = slots;
        tile_rows_ = cap.tile_rows;
        tile_columns_ = cap.tile_columns;
        grid_tiles_ = cap.grid_tiles;
        ShaderDefines region_defines;
        if (coverage) {
            region_defines.push_back({"PENUMBRA_SBS_REGION_BASE", std::to_string(uint64_t(slots) * PENUMBRA_SBS_TRIANGLE_WORDS) + "u"});
            region_defines.push_back({"PENUMBRA_SBS_REGION_CAPACITY", std::to_string(regions) + "u"});
            region_defines.push_back({"PENUMBRA_SBS_REGION_MAX_TEXELS", std::to_string(options_.coverage_texels) + "u"});
            region_defines.push_back({"PENUMBRA_SBS_OCCUPANCY_BASE",
                                      std::to_string(uint64_t(slots) * PENUMBRA_SBS_TRIANGLE_WORDS + uint64_t(regions) * region_words) + "u"});
            region_defines.push_back({"PENUMBRA_SBS_OCCUPANCY_ROW", std::to_string(occupancy_row) + "u"});
            tile_base_ = uint64_t(slots) * PENUMBRA_SBS_TRIANGLE_WORDS + uint64_t(regions) * region_words + occupancy_words;
            region_defines.push_back({"PENUMBRA_SBS_TILE_BASE", std::to_string(tile_base_) + "u"});
            region_defines.push_back({"PENUMBRA_SBS_TILE_ROWS", std::to_string(tile_rows_) + "u"});
            region_defines.push_back({"PENUMBRA_SBS_TILE_COLUMNS", std::to_string(tile_columns_) + "u"});
            regions_ = regions;
            region_defines.push_back(
                {"PENUMBRA_SBS_STENCIL_BLOCKS", std::to_string(compute                       ? 0xFFFFFFFFu
                                                               : options_.skips.empty_blocks ? gl::kOccupancyStencilBlocks
                                                                                             : 0u) +
                                                    "u"});
        }
        const auto light_pass_program = [&](bool deferring) {
            ShaderDefines d = defines;
            d.push_back({"PENUMBRA_SBS_DEFERRED", deferring ? "1" : "0"});
            d.push_back({"PENUMBRA_SBS_COVERAGE", deferring && coverage ? "1" : "0"});
            if (deferring) d.insert(d.end(), region_defines.begin(), region_defines.end());
            return gl::buildProgram({"penumbra/sample_based_soft/light_pass.vert.glsl", "penumbra/sample_based_soft/light_pass.geom.glsl",
                                     "penumbra/sample_based_soft/light_pass.frag.glsl"},
                                    d, library);
        };
        if (!compute) light_pass_ = light_pass_program(deferred);
        if (deferred) {
            // Deferred pairs: the geometry stage stores triangles (two more storage blocks), the
            // fragment stage appends pairs, a compute pass works them (checked here, throws); the
            // program without deferral redraws the draws that overflow, under predicates of its own.
            const GLint compute_blocks = gl::getInteger(GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS);
            const GLint geometry_blocks = gl::getInteger(GL_MAX_GEOMETRY_SHADER_STORAGE_BLOCKS);
            PENUMBRA_CHECK((compute || geometry_blocks >= (options_.count_work ? 3 : 2)) && compute_blocks >= needed + 5,
                           "penumbra::SampleBasedSoftShadows: deferred_pairs needs ", options_.count_work ? 3 : 2,
                           " geometry and ", needed + 5, " compute storage blocks; the driver has ", geometry_blocks, " and ",
                           compute_blocks, "; set deferred_pairs = 0");
            const uint32_t triangles = slots;
            const uint64_t max_block = uint64_t(gl::getInteger64(GL_MAX_SHADER_STORAGE_BLOCK_SIZE));
            const uint32_t test_words = cap.test_words, fragments = cap.fragments;
            const uint64_t pair_bytes = cap.pair_bytes, test_bytes = cap.test_bytes, fragment_bytes = cap.fragment_bytes;
            const uint64_t table_bytes = cap.table_bytes, triangle_bytes = cap.triangle_bytes;
            fragment_capacity_ = fragments;
            PENUMBRA_CHECK(pair_bytes <= max_block && triangle_bytes <= max_block && test_bytes <= max_block &&
                               fragment_bytes <= max_block,
                           "penumbra::SampleBasedSoftShadows: deferred_pairs = ", options_.deferred_pairs, " (", pair_bytes,
                           " bytes), ", triangles, " triangle slots (", triangle_bytes, " bytes), ", test_words,
                           " exact-test words (", test_bytes, " bytes) and ", fragments, " fragments (", fragment_bytes,
                           " bytes) must each fit GL_MAX_SHADER_STORAGE_BLOCK_SIZE = ", max_block);
            // The group counts of each compute pass (PENUMBRA_SBS_ARGS_KIND: 0 pairs, 1 exact tests, 2 tables).
            const auto args_program = [&](uint32_t kind, uint32_t capacity, bool round = false) {
                ShaderDefines d = defines;
                if (round) d.push_back({"PENUMBRA_SBS_ARGS_ROUND", "1"});
                if (compute && (kind == 0 || round) && options_.overflow_windows > 0)
                    d.push_back({"PENUMBRA_SBS_ARGS_WINDOWS", std::to_string(options_.overflow_windows)});
                if (kind == 4 || kind == 5) d.insert(d.end(), region_defines.begin(), region_defines.end());  // the tiles
                d.push_back({"PENUMBRA_SBS_ARGS_KIND", std::to_string(kind)});
                d.push_back({"PENUMBRA_SBS_ARGS_CAPACITY", std::to_string(capacity) + "u"});
                d.push_back({"PENUMBRA_SBS_ARGS_FRAGMENT_CAPACITY", std::to_string(fragments) + "u"});
                return gl::buildComputeProgram("penumbra/sample_based_soft/light_pass_args.comp.glsl", d, library);
            };
            deferral_args_ = args_program(0, options_.deferred_pairs);
            test_args_ = args_program(1, test_words);
            table_args_ = args_program(2, options_.deferred_pairs);
            light_compute_ = gl::buildComputeProgram("penumbra/sample_based_soft/light_pass.comp.glsl", defines, library);
            if (coverage) {
                region_args_ = args_program(3, regions, compute);
                ShaderDefines d = defines;
                d.insert(d.end(), region_defines.begin(), region_defines.end());
                light_coverage_ = gl::buildComputeProgram("penumbra/sample_based_soft/light_pass_coverage.comp.glsl", d, library);
                d.push_back({"PENUMBRA_SBS_COVERAGE_BITS", "1"});
                coverage_bits_ = gl::buildComputeProgram("penumbra/sample_based_soft/light_pass_coverage.comp.glsl", d, library);
                coverage_bit_groups_ = uint32_t(detail::divUp(occupancy_words, PENUMBRA_SBS_COVERAGE_GROUP));
                d.back() = {"PENUMBRA_SBS_COVERAGE_COUNT", "1"};
                if (compute && options_.overflow_windows > 0) d.push_back({"PENUMBRA_SBS_COVERAGE_WINDOWS", "1"});
                coverage_count_ = gl::buildComputeProgram("penumbra/sample_based_soft/light_pass_coverage.comp.glsl", d, library);
                if (compute && options_.overflow_windows > 0) d.pop_back();
                d.back() = {"PENUMBRA_SBS_COVERAGE_SCAN", "1"};
                coverage_scan_ = gl::buildComputeProgram("penumbra/sample_based_soft/light_pass_coverage.comp.glsl", d, library);
                item_args_ = args_program(5, regions);
            }
            ShaderDefines per_fragment = defines;
            per_fragment.push_back({"PENUMBRA_SBS_PER_FRAGMENT", "1"});
            light_fragments_ = gl::buildComputeProgram("penumbra/sample_based_soft/light_pass.comp.glsl", per_fragment, library);
            light_tests_ = gl::buildComputeProgram("penumbra/sample_based_soft/light_pass_tests.comp.glsl", defines, library);
            light_tables_ = gl::buildComputeProgram("penumbra/sample_based_soft/light_pass_tables.comp.glsl", defines, library);
            tests_ = gl::Buffer(test_bytes);
            table_pairs_ = gl::Buffer(table_bytes);
            fragments_ = gl::Buffer(fragment_bytes);
            if (compute) {
                // The caster setup, and the coverage pass that works its pairs itself after an overflow.
                ShaderDefines d = defines;
                d.insert(d.end(), region_defines.begin(), region_defines.end());
                setup_program_ = gl::buildComputeProgram("penumbra/sample_based_soft/light_pass_setup.comp.glsl", d, library);
                d.push_back({"PENUMBRA_SBS_SETUP_GATE", "1"});
                setup_gate_ = gl::buildComputeProgram("penumbra/sample_based_soft/light_pass_setup.comp.glsl", d, library);
                d.pop_back();
                d.push_back({"PENUMBRA_SBS_COVERAGE_INLINE", "1"});
                light_inline_ = gl::buildComputeProgram("penumbra/sample_based_soft/light_pass_coverage.comp.glsl", d, library);
                inline_args_ = args_program(4, 0);
            } else {
                light_fragment_ = light_pass_program(false);
                ShaderDefines fallback_defines = defines;
                fallback_defines.push_back({"PENUMBRA_SBS_FALLBACK_PREDICATE", "1"});
                fallback_blocks_ = gl::buildProgram(
                    {"penumbra/alias_free_hard/blocks.vert.glsl", "penumbra/sample_based_soft/blocks.frag.glsl"},
                    fallback_defines, library);
                for (uint32_t q = 0; q < options_.max_list_blocks; ++q) fallback_queries_.push_back(gl::OcclusionQuery::create());
            }
            deferral_ = gl::Buffer(PENUMBRA_SBS_DEFERRAL_WORDS * 4);
            pairs_ = gl::Buffer(pair_bytes);
            triangles_ = gl::Buffer(triangle_bytes);
        }
        if (!compute)
            blocks_ = gl::buildProgram({"penumbra/alias_free_hard/blocks.vert.glsl", "penumbra/sample_based_soft/blocks.frag.glsl"},
                                       defines, library);
        resolve_ = gl::buildComputeProgram("penumbra/sample_based_soft/resolve.comp.glsl", defines, library);
        const auto occupancy_program = [&](uint32_t kind) {
            ShaderDefines d = defines;
            d.push_back({"PENUMBRA_SBS_OCCUPANCY", std::to_string(kind)});
            return gl::buildProgram({"penumbra/common/fullscreen.vert.glsl", "penumbra/sample_based_soft/occupancy.frag.glsl"}, d,
                                    library);
        };
        if (options_.skips.closed_casters && !options_.count_work && !compute) {
            near_blocks_ = occupancy_program(2);
            for (uint32_t q = 0; q < options_.max_list_blocks; ++q) near_queries_.push_back(gl::OcclusionQuery::create());
        }
        if (options_.skips.empty_blocks && !compute) {
            occupancy_ = occupancy_program(0);
            if (options_.skips.closed_casters) near_stencil_ = occupancy_program(1);
            stencil_ = gl::Renderbuffer::create();
            glNamedRenderbufferStorage(stencil_.id(), GL_STENCIL_INDEX8, static_cast<GLsizei>(options_.grid_width),
                                       static_cast<GLsizei>(options_.grid_height));
        }
        if (options_.skips.silhouettes) {
            ShaderDefines edge_defines;  // the influence setup's, uncut: the cut is a triangle's
            for (const auto& d : defines)
                if (d.name != "PENUMBRA_INFLUENCE_CUT") edge_defines.push_back(d);
            edge_defines.push_back({"PENUMBRA_INFLUENCE_CUT", "0"});
            silhouettes_ = gl::buildProgram({"penumbra/sample_based_soft/light_pass.vert.glsl",
                                             "penumbra/sample_based_soft/silhouettes.geom.glsl",
                                             "penumbra/sample_based_soft/silhouettes.frag.glsl"},
                                            edge_defines, library);
            edge_defines.push_back({"PENUMBRA_SBS_NEAR_PASS", "1"});
            silhouettes_near_ = gl::buildProgram({"penumbra/sample_based_soft/light_pass.vert.glsl",
                                                  "penumbra/sample_based_soft/silhouettes.geom.glsl",
                                                  "penumbra/sample_based_soft/silhouettes.frag.glsl"},
                                                 edge_defines, library);
            marks_ = gl::Buffer(size_t(options_.grid_width) * options_.grid_height * 4);
        }
        ubo_alignment_ = static_cast<uint32_t>(gl::getInteger(GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT));
        ssbo_alignment_ = static_cast<uint32_t>(gl::getInteger(GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT));
        param_stride_ = static_cast<uint32_t>(detail::divUp(sizeof(SbsParams), ubo_alignment_) * ubo_alignment_);
        params_staging_.assign(size_t(param_stride_) * (1 + kSlotsPerBlock * options_.max_list_blocks), 0u);
        params_ = gl::Buffer(params_staging_.size(), nullptr, GL_DYNAMIC_STORAGE_BIT);
        influence_params_ = gl::Buffer(sizeof(InfluenceRegionParams), &influence_.params);
        const std::vector<glm::dvec4> world = sampleBasedSoftSampleTable(sets_, options_.rotations);
        samples_ = gl::Buffer::fromVector(world);
        sample_reach_ = sampleBasedSoftSampleReach(world, size_t(n_) * k_ * options_.rotations, sets_.frame.center);
        work_ = gl::Buffer(PENUMBRA_SBS_WORK_WORDS * 4);
        lists_.frustum = gl::Buffer(sizeof(SampleListsFrustum));
        dummy_ = gl::Buffer(16);
        if (!compute) {
            framebuffer_ = gl::Framebuffer::create();
            glNamedFramebufferParameteri(framebuffer_.id(), GL_FRAMEBUFFER_DEFAULT_WIDTH, static_cast<GLint>(options_.grid_width));
            glNamedFramebufferParameteri(framebuffer_.id(), GL_FRAMEBUFFER_DEFAULT_HEIGHT,
                                         static_cast<GLint>(options_.grid_height));
            empty_vao_ = gl::VertexArray::create();
            for (uint32_t q = 0; q < options_.max_list_blocks; ++q) block_queries_.push_back(gl::OcclusionQuery::create());
        }
        if (options_.skips.empty_blocks && !compute) {
            glNamedFramebufferRenderbuffer(framebuffer_.id(), GL_STENCIL_ATTACHMENT, GL_RENDERBUFFER, stencil_.id());
            const GLenum complete = glCheckNamedFramebufferStatus(framebuffer_.id(), GL_DRAW_FRAMEBUFFER);
            PENUMBRA_CHECK(complete == GL_FRAMEBUFFER_COMPLETE, "penumbra::SampleBasedSoftShadows: the light pass's ",
                           options_.grid_width, " x ", options_.grid_height,
                           " framebuffer with a GL_STENCIL_INDEX8 attachment (skips.empty_blocks) is incomplete (status 0x",
                           std::hex, complete, std::dec, "); set skips.empty_blocks = false");
        }
        if (options_.timings) {
            timers_.reserve(3);
            for (int t = 0; t < 3; ++t) timers_.emplace_back();
        }
        vp_ = view_projection;
        light_.view_projection = vp_;
        light_.light = glm::vec4(glm::vec3(influence_.frame.center), 1.0f);
        gl::checkErrors("penumbra::SampleBasedSoftShadows");
    }
    SampleBasedSoftShadows(SampleBasedSoftShadows&&) noexcept = default;
    SampleBasedSoftShadows& operator=(SampleBasedSoftShadows&&) noexcept = default;
    SampleBasedSoftShadows(const SampleBasedSoftShadows&) = delete;
    SampleBasedSoftShadows& operator=(const SampleBasedSoftShadows&) = delete;

    const SampleBasedSoftGpuOptions& options() const { return options_; }
    uint32_t wordsPerSample() const { return words_; }

    /// Load time: lists, masks and visibility for up to `max_samples` view samples. Throws.
    void reserve(uint32_t max_samples) {
        const SampleListsSetup s = sampleListsSetup(options_.grid_width, options_.grid_height, max_samples);
        builder_.reserve(s);
        if (!lists_.reserve(s, max_samples)) return;
        const size_t samples = lists_.samples;
        masks_ = gl::Buffer(samples * words_ * 4);
        if (options_.skips.closed_casters)  // per sample, then per texel
            near_ = gl::Buffer((samples + size_t(options_.grid_width) * options_.grid_height) * 4);
        visibility_ = gl::Buffer(samples * 4);
        reserved_ = lists_.samples;
        gl::checkErrors("penumbra::SampleBasedSoftShadows::reserve");
    }

    /// Load-time checks of the integrator's ranges (GL queries; throws naming the range).
    void validate(const SampleBufferInput& input, uint32_t sample_count, const BufferRange& lut_table,
                  const SbsFrameBuffers& frame = {}) const {
        const SampleListsSetup s = sampleListsSetup(options_.grid_width, options_.grid_height, sample_count);
        builder_.validate(s, input, buffers(), listOptions());
        validateFrame(sample_count, lut_table, frame);
    }

    void validate(const SampleDepthInput& input, const BufferRange& lut_table, const SbsFrameBuffers& frame = {}) const {
        const uint32_t n = input.view.width * input.view.height;
        const SampleListsSetup s = sampleListsSetup(options_.grid_width, options_.grid_height, n);
        builder_.validate(s, input, buffers(), listOptions());
        validateFrame(n, lut_table, frame);
    }

    /// Every pass for buffer input (see the summary). `lut_table` may be empty in Brute mode.
    Status run(const SampleBufferInput& input, uint32_t sample_count, const BufferRange& lut_table,
               const DrawCasters& draw_casters, const SbsFrameBuffers& frame = {}, const DrawAdjacency& draw_adjacency = {}) {
        const Status s = begin(sample_count, lut_table, options_.light_pass == SoftLightPass::Raster && draw_casters, frame,
                               &draw_adjacency);
        if (s != Status::Ok) return s;
        if (!timers_.empty()) timers_[0].begin();
        const Status built = builder_.build(setup_, light_, input, buffers(), listOptions(), listBuild());
        if (!timers_.empty()) timers_[0].end();
        if (built != Status::Ok) return built;
        lightPassAndResolve(lut_table, draw_casters, frame);
        return Status::Ok;
    }

    /// Every pass for depth input (positions reconstructed on the GPU from the engine's depth
    /// buffer; sample count = view width * height, id = y * width + x). The normal texture may be 0.
    Status run(const SampleDepthInput& input, const BufferRange& lut_table, const DrawCasters& draw_casters,
               const SbsFrameBuffers& frame = {}, const DrawAdjacency& draw_adjacency = {}) {
        const uint64_t n = uint64_t(input.view.width) * input.view.height;
        if (n > reserved_) return fail(Status::NotReserved);
        const Status s = begin(static_cast<uint32_t>(n), lut_table, options_.light_pass == SoftLightPass::Raster && draw_casters,
                               frame, &draw_adjacency);
        if (s != Status::Ok) return s;
        if (!timers_.empty()) timers_[0].begin();
        const Status built = builder_.build(setup_, light_, input, buffers(), listOptions(), listBuild());
        if (!timers_.empty()) timers_[0].end();
        if (built != Status::Ok) return built;
        lightPassAndResolve(lut_table, draw_casters, frame);
        return Status::Ok;
    }

    /// SoftLightPass::Compute, buffer input: every pass, the casters as `caster_count` ranges
    /// (CasterBuffer; ranges of 0 triangles are skipped). Misuse (the Raster light pass, a stride
    /// below 12 or not a multiple of 4, a range too small for its triangles, a misaligned offset)
    /// returns a Status and does nothing.
    Status run(const SampleBufferInput& input, uint32_t sample_count, const BufferRange& lut_table, const CasterBuffer* casters,
               uint32_t caster_count, const SbsFrameBuffers& frame = {}) {
        return runCompute(input, sample_count, lut_table, casters, caster_count, frame);
    }

    /// SoftLightPass::Compute, depth input (as the DrawCasters overload).
    Status run(const SampleDepthInput& input, const BufferRange& lut_table, const CasterBuffer* casters, uint32_t caster_count,
               const SbsFrameBuffers& frame = {}) {
        const uint64_t n = uint64_t(input.view.width) * input.view.height;
        if (n > reserved_) return fail(Status::NotReserved);
        return runCompute(input, static_cast<uint32_t>(n), lut_table, casters, caster_count, frame);
    }

    /// Load-time check of CasterBuffer ranges against their buffers (GL queries; throws naming the
    /// range): what run() checks, plus the buffers' sizes.
    void validateCasters(const CasterBuffer* casters, uint32_t caster_count) const {
        const char* f = "SampleBasedSoftShadows::validateCasters";
        PENUMBRA_CHECK(options_.light_pass == SoftLightPass::Compute, "penumbra::", f,
                       ": casters as buffers need options.light_pass = SoftLightPass::Compute");
        gl::validateCasterBuffers(casters, caster_count, ssbo_alignment_, f);
    }

    /// What the last run did (reads back and waits: tools, tests, benchmarks).
    SampleBasedSoftFrame readFrame() const {
        SampleBasedSoftFrame f;
        f.statistics = SampleListBuilder::readStatistics(setup_, buffers());
        f.passes = static_cast<uint32_t>(
            std::min<uint64_t>(detail::divUp(f.statistics.max_list_length, options_.list_block), options_.max_list_blocks));
        const std::vector<uint32_t> w = work_.download<uint32_t>(0, PENUMBRA_SBS_WORK_WORDS);
        f.fragments = w[PENUMBRA_SBS_WORK_FRAGMENTS];
        f.pairs = w[PENUMBRA_SBS_WORK_PAIRS];
        f.pairs_ignored = w[PENUMBRA_SBS_WORK_PAIRS_IGNORED];
        f.pairs_unproven = w[PENUMBRA_SBS_WORK_PAIRS_UNPROVEN];
        f.uncertain_bits = w[PENUMBRA_SBS_WORK_UNCERTAIN_BITS];
        f.exact_tests = w[PENUMBRA_SBS_WORK_EXACT_TESTS];
        f.planes_unproven = w[PENUMBRA_SBS_WORK_PLANES_UNPROVEN];
        f.overflow = w[PENUMBRA_SBS_WORK_OVERFLOW];
        f.fragments_skipped = w[PENUMBRA_SBS_WORK_FRAGMENTS_SKIPPED];
        f.triangles_culled = w[PENUMBRA_SBS_WORK_TRIANGLES_CULLED];
        f.pairs_cut = w[PENUMBRA_SBS_WORK_PAIRS_CUT];
        f.pairs_hard = w[PENUMBRA_SBS_WORK_PAIRS_HARD];
        f.pairs_recovered = w[PENUMBRA_SBS_WORK_PAIRS_RECOVERED];
        f.pairs_front = w[PENUMBRA_SBS_WORK_PAIRS_FRONT];
        f.pairs_wedged = w[PENUMBRA_SBS_WORK_PAIRS_WEDGED];
        f.pairs_deferred = w[PENUMBRA_SBS_WORK_DEFERRED];
        f.deferral_fallbacks = w[PENUMBRA_SBS_WORK_FALLBACKS];
        f.caster_indices_out_of_range = w[PENUMBRA_SBS_WORK_BAD_INDICES];
        f.chunks = w[PENUMBRA_SBS_WORK_CHUNKS];
        if (!timers_.empty()) {
            f.lists_ns = timers_[0].nanoseconds();
            f.light_pass_ns = timers_[1].nanoseconds();
            f.resolve_ns = timers_[2].nanoseconds();
        }
        return f;
    }
    /// The executor's masks / visibility of the last run (waits): sample_count * words / sample_count.
    std::vector<uint32_t> readMasks() const { return masks_.download<uint32_t>(0, size_t(setup_.sample_count) * words_); }
    std::vector<float> readVisibility() const { return visibility_.download<float>(0, setup_.sample_count); }
    /// SoftSkips::silhouettes: the last run's texel marks (W x H, row-major; bit 0 = some potential
    /// silhouette's region covers the texel, bit 1 = a view sample there has a triangle's edges
    /// opened by the oracle's coplanar rule; nonzero = full test); empty when the skip is off. Waits.
    std::vector<uint32_t> readMarks() const {
        if (!options_.skips.silhouettes) return {};
        return marks_.download<uint32_t>(0, size_t(options_.grid_width) * options_.grid_height);
    }

    BufferRange masks() const { return {masks_.id(), 0, masks_.size()}; }
    BufferRange visibility() const { return {visibility_.id(), 0, visibility_.size()}; }
    SampleListsBuffers buffers() const { return lists_.ranges(); }
    const SampleListsSetup& setup() const { return setup_; }
    /// The light pass's program (with deferred_pairs the deferring one) and, with deferred_pairs, the
    /// fragment-stage program that redraws overflowing draws (0 otherwise): your DrawCasters runs
    /// with either bound.
    GLuint lightPassProgram() const { return light_pass_.id(); }
    GLuint fallbackLightPassProgram() const { return light_fragment_.id(); }
    uint32_t reservedSamples() const { return reserved_; }
    /// GPU memory this pipeline allocated, in bytes: its buffers, the list storage and the raster
    /// pass's stencil (skips.empty_blocks, a byte per texel). Fixed by the constructor and
    /// reserve(): a frame allocates nothing, whatever its triangles and pairs.
    uint64_t memoryBytes() const {
        uint64_t bytes = stencil_.id() ? uint64_t(options_.grid_width) * options_.grid_height : 0;
        for (const gl::Buffer* b : {&deferral_, &pairs_, &triangles_, &tests_, &table_pairs_, &fragments_, &marks_, &near_, &params_,
                                    &influence_params_, &samples_, &work_, &dummy_, &masks_, &visibility_, &lists_.counts,
                                    &lists_.offsets, &lists_.positions, &lists_.ids, &lists_.slots, &lists_.texels, &lists_.header,
                                    &lists_.frustum})
            bytes += b->size();
        return bytes;
    }
    /// The GPU memory a pipeline built with these options, light sample sets and influence setup
    /// allocates at most, through reserve(max_samples): an upper bound of memoryBytes(), known
    /// before construction (no GL call), with the parameter slots at the largest uniform-buffer
    /// offset alignment GL allows (256 bytes; drivers' smaller alignments allocate less). Frames
    /// allocate nothing beyond it, whatever their triangles and pairs: what does not fit the
    /// deferred buffers is split into chunks (SampleBasedSoftFrame::chunks).
    static uint64_t memoryBound(const SampleBasedSoftGpuOptions& options, const LightSampleSets& sets,
                                const InfluenceRegionSetup& influence, uint32_t max_samples) {
        validateSampleBasedSoftGpuOptions(options);
        PENUMBRA_CHECK(uint32_t(influence.width()) == options.grid_width && uint32_t(influence.height()) == options.grid_height,
                       "penumbra::SampleBasedSoftShadows::memoryBound: the influence setup's grid ", influence.width(), " x ",
                       influence.height(), " differs from the options' ", options.grid_width, " x ", options.grid_height);
        const bool compute = options.light_pass == SoftLightPass::Compute;
        const uint64_t texels = uint64_t(options.grid_width) * options.grid_height;
        uint64_t bytes = options.skips.empty_blocks && !compute ? texels : 0u;  // the stencil
        if (options.deferred_pairs > 0) {
            const Capacities c = capacities(options, influence.sides());
            bytes += PENUMBRA_SBS_DEFERRAL_WORDS * 4 + c.pair_bytes + c.test_bytes + c.fragment_bytes + c.table_bytes + c.triangle_bytes;
        }
        if (options.skips.silhouettes) bytes += texels * 4;  // the texel marks
        bytes += detail::divUp(sizeof(SbsParams), size_t(256)) * 256 * (1 + kSlotsPerBlock * uint64_t(options.max_list_blocks));
        bytes += sizeof(InfluenceRegionParams) + PENUMBRA_SBS_WORK_WORDS * 4 + 16;  // + the dummy binding
        bytes += (uint64_t(sets.count()) * sets.sets() + 1) * options.rotations * sizeof(glm::dvec4);  // the sample table
        // The lists (lengths, offsets, header, frustum; per sample its position, id, slot and
        // texel), then per sample its mask, visibility and, with closed_casters, near flag.
        const SampleListsSetup lists = sampleListsSetup(options.grid_width, options.grid_height, max_samples);
        const uint64_t samples = std::max<uint32_t>(max_samples, 1);
        const uint64_t words = (sets.count() + 31) / 32;
        bytes += lists.counts_bytes + lists.offsets_bytes + lists.header_bytes + sizeof(SampleListsFrustum) + samples * 28;
        bytes += samples * (words + 1) * 4;
        if (options.skips.closed_casters) bytes += (samples + texels) * 4;
        return bytes;
    }
    /// The light grid's view-projection (the influence setup's, which the lists use too).
    const glm::mat4& viewProjection() const { return vp_; }

private:
    SampleBasedSoftGpuOptions options_;
    SbsBindings bindings_;
    SampleListBuilder builder_;
    LightSampleSets sets_;
    LightLutSetup lut_;
    bool has_lut_ = false;
    InfluenceRegionSetup influence_;
    glm::mat4 vp_{1.0f};
    uint32_t n_ = 0, k_ = 0, words_ = 0;
    double sample_reach_ = 0.0;  // sampleBasedSoftSampleReach of the sample table
    gl::Program light_pass_, blocks_, resolve_, silhouettes_, silhouettes_near_, occupancy_, near_stencil_, near_blocks_;
    // Deferred pairs (options.deferred_pairs > 0): the compute pass, its arguments, the fragment-stage
    // program and the list-block predicates of the redraw after an overflow.
    gl::Program light_compute_, light_coverage_, coverage_bits_, region_args_, light_fragments_, deferral_args_, light_fragment_, fallback_blocks_, test_args_, light_tests_,
        table_args_, light_tables_;
    gl::Buffer deferral_, pairs_, triangles_, tests_, table_pairs_, fragments_;
    // SoftLightPass::Compute: the caster setup, the coverage pass working its pairs itself after an
    // overflow, and its group counts; the triangle slots (and records) a deferred run holds.
    gl::Program setup_program_, setup_gate_, light_inline_, inline_args_;
    uint32_t slots_ = 0;
    uint32_t fragment_capacity_ = 0;  // deferred fragments (with deferred_pairs)
    uint32_t coverage_bit_groups_ = 0;  // the occupancy bits' groups (coverage_texels)
    // The coverage pass's work items: tile counts per record, their scan into first items.
    static constexpr uint64_t kCoverageItemIterations = 16384;
    /// The deferred passes' capacities and buffer sizes the options ask for (with deferred_pairs;
    /// the coverage records with coverage_texels or the compute light pass).
    struct Capacities {
        uint32_t slots = 0, regions = 0, region_words = 0, test_words = 0, fragments = 0;
        uint32_t tile_rows = 8, tile_columns = 32;
        uint64_t grid_tiles = 0, occupancy_words = 0;
        uint64_t pair_bytes = 0, test_bytes = 0, fragment_bytes = 0, table_bytes = 0, triangle_bytes = 0;
    };
    static Capacities capacities(const SampleBasedSoftGpuOptions& o, int influence_sides) {
        Capacities c;
        const bool compute = o.light_pass == SoftLightPass::Compute, deferred = o.deferred_pairs > 0;
        // Coverage (coverage_texels; every region with the compute light pass): records after the
        // triangle slots.
        c.slots = o.deferred_triangles ? o.deferred_triangles : compute ? 1u << 17 : std::max<uint32_t>(1, o.deferred_pairs / 4);
        const bool coverage = compute || (deferred && o.coverage_texels > 0);
        c.regions = !coverage ? 0u : compute ? c.slots : o.deferred_regions ? o.deferred_regions : std::min<uint32_t>(c.slots, 1u << 16);
        c.region_words = 2u + 2u * uint32_t(PENUMBRA_INFLUENCE_MAX_VERTICES(influence_sides));
        c.occupancy_words = coverage ? uint64_t((o.grid_width + 31) / 32) * o.grid_height : 0u;
        // The coverage pass's work items: tiles of tile_rows x tile_columns texels, each within
        // ~16k loop iterations (llvmpipe silently ends an invocation's loops at 65 535 in all):
        // per row the polygon's edges and an occupancy word, per texel a list block's appends
        // (wedge tests, pairs, the straddling fragment's empty pairs: 3 list_block + 4).
        const uint64_t per_texel = 3ull * o.list_block + 4;
        const uint64_t per_row = uint64_t(PENUMBRA_INFLUENCE_MAX_VERTICES(influence_sides)) + 4;
        while (c.tile_columns > 1 && per_row + c.tile_columns * per_texel > kCoverageItemIterations) c.tile_columns /= 2;
        c.tile_rows = static_cast<uint32_t>(std::clamp<uint64_t>(kCoverageItemIterations / (per_row + c.tile_columns * per_texel), 1, 8));
        c.grid_tiles = detail::divUp(o.grid_width, c.tile_columns) * detail::divUp(o.grid_height, c.tile_rows);
        if (!deferred) return c;
        // Per record its tile count, 2 box words and first item; per tile of the grid its longest list.
        const uint64_t tile_words = coverage ? 4ull * c.regions + c.grid_tiles : 0u;
        c.test_words = o.deferred_tests ? o.deferred_tests : std::max<uint32_t>(1, o.deferred_pairs / 4);
        c.fragments = o.deferred_fragments ? o.deferred_fragments : std::max<uint32_t>(1, o.deferred_pairs / 2);
        c.pair_bytes = uint64_t(o.deferred_pairs) * 8;
        c.test_bytes = uint64_t(c.test_words) * 16;
        c.fragment_bytes = uint64_t(c.fragments) * 8;
        c.table_bytes = uint64_t(o.deferred_pairs) * 4;  // every pair may need the tables
        c.triangle_bytes = uint64_t(c.slots) * 4 * PENUMBRA_SBS_TRIANGLE_WORDS + uint64_t(c.regions) * 4 * c.region_words +
                           4 * c.occupancy_words + 4 * tile_words;
        return c;
    }
    gl::Program coverage_count_, coverage_scan_, item_args_;
    uint32_t tile_rows_ = 8, tile_columns_ = 32, regions_ = 0;
    uint64_t tile_base_ = 0;   // the tile counts' first word in the triangles buffer
    uint64_t grid_tiles_ = 0;  // tiles of the grid (their longest lists follow the records' first items)
    std::vector<gl::OcclusionQuery> fallback_queries_;
    gl::Renderbuffer stencil_;  // SoftSkips::empty_blocks: W x H, non-empty list blocks per texel
    /// Parameter slots per list block: closed, open, closed again (SoftSkips::closed_casters' second
    /// pass), and the same three for count_work's complement draws.
    static constexpr uint32_t kSlotsPerBlock = 6;
    gl::Buffer marks_;                                // SoftSkips::silhouettes: W x H texel marks
    gl::Buffer near_;                                 // SoftSkips::closed_casters: per sample
    const DrawAdjacency* draw_adjacency_ = nullptr;   // this run's (begin() .. the light pass)
    gl::Buffer params_, influence_params_, samples_, work_, dummy_;
    SampleListStorage lists_;
    gl::Buffer masks_, visibility_;
    gl::Framebuffer framebuffer_;
    gl::VertexArray empty_vao_;
    std::vector<gl::OcclusionQuery> block_queries_;
    /// SoftSkips::closed_casters, count_work off: per list block, the closed casters' second pass is
    /// needed (some texel's block holds a sample flagged near a kept closed triangle).
    std::vector<gl::OcclusionQuery> near_queries_;
    std::vector<gl::GpuTimer> timers_;  // options.timings: lists, light pass, resolve
    std::vector<uint8_t> params_staging_;
    uint32_t ubo_alignment_ = 256, ssbo_alignment_ = 256, param_stride_ = 512;
    uint32_t reserved_ = 0;
    SampleListsSetup setup_;
    SampleListsLight light_;

    void validateFrame(uint32_t sample_count, const BufferRange& lut_table, const SbsFrameBuffers& frame) const {
        const char* f = "SampleBasedSoftShadows::validate";
        if (options_.mode != SoftMode::Brute) gl::validateRange(lut_table, lut_.tableBytes(), "lut table", f, ssbo_alignment_);
        if (!frame.sets.empty()) gl::validateRange(frame.sets, uint64_t(sample_count) * 4, "sets", f, ssbo_alignment_);
        if (!frame.masks.empty())
            gl::validateRange(frame.masks, uint64_t(sample_count) * words_ * 4, "masks", f, ssbo_alignment_);
        if (!frame.visibility.empty())
            gl::validateRange(frame.visibility, uint64_t(sample_count) * 4, "visibility", f, ssbo_alignment_);
    }

    /// `casters`: the run's casters fit the light pass (a callback for Raster, checked buffers for
    /// Compute); `draw_adjacency` null for Compute.
    Status begin(uint32_t sample_count, const BufferRange& lut_table, bool casters, const SbsFrameBuffers& frame,
                 const DrawAdjacency* draw_adjacency) {
        if (reserved_ == 0 || sample_count > reserved_) return fail(Status::NotReserved);
        if (!casters || (options_.skips.silhouettes && !(draw_adjacency && *draw_adjacency))) return fail(Status::InvalidArgument);
        draw_adjacency_ = draw_adjacency;
        if (options_.mode != SoftMode::Brute && !lut_table.holds(lut_.tableBytes())) return fail(Status::RangeTooSmall);
        if (!frame.sets.empty() && !frame.sets.holds(uint64_t(sample_count) * 4)) return fail(Status::RangeTooSmall);
        if (!frame.masks.empty() && !frame.masks.holds(uint64_t(sample_count) * words_ * 4)) return fail(Status::RangeTooSmall);
        if (!frame.visibility.empty() && !frame.visibility.holds(uint64_t(sample_count) * 4)) return fail(Status::RangeTooSmall);
        for (const BufferRange* r : {&lut_table, &frame.sets, &frame.masks, &frame.visibility})
            if (!r->empty() && r->offset % ssbo_alignment_ != 0) return fail(Status::Misaligned);
        setup_ = sampleListsSetup(options_.grid_width, options_.grid_height, sample_count);  // <= reserved: no throw
        return Status::Ok;
    }

    static Status fail(Status s) {
        PENUMBRA_ASSERT(s == Status::Ok && "penumbra::SampleBasedSoftShadows: per-frame misuse (see the returned Status)");
        return s;
    }

    /// The compute light pass's run() for either input.
    template <class Input>
    Status runCompute(const Input& input, uint32_t sample_count, const BufferRange& lut_table, const CasterBuffer* casters,
                      uint32_t caster_count, const SbsFrameBuffers& frame) {
        const Status c = checkCasters(casters, caster_count);
        if (c != Status::Ok) return c;
        const Status s = begin(sample_count, lut_table, true, frame, nullptr);
        if (s != Status::Ok) return s;
        if (!timers_.empty()) timers_[0].begin();
        const Status built = builder_.build(setup_, light_, input, buffers(), listOptions(), listBuild());
        if (!timers_.empty()) timers_[0].end();
        if (built != Status::Ok) return built;
        lightPassAndResolve(lut_table, {}, frame, casters, caster_count);
        return Status::Ok;
    }

    /// run()'s per-frame check of the caster ranges (no GL call).
    Status checkCasters(const CasterBuffer* casters, uint32_t count) const {
        if (options_.light_pass != SoftLightPass::Compute) return fail(Status::InvalidArgument);
        const Status s = checkCasterBuffers(casters, count, ssbo_alignment_);
        return s == Status::Ok ? s : fail(s);
    }

    SampleListsOptions listOptions() const {
        SampleListsOptions o;
        o.cull_back_facing = false;  // every sample tested: a soft light may reach past the centre's terminator
        o.depth_range = LightDepthRange::Unclipped;
        return o;
    }
    SampleListsBuild listBuild() const {
        SampleListsBuild b;
        b.fit_frustum = false;  // the influence regions are built on the host's grid
        b.statistics = true;    // the predicate pass reads max_list_length
        return b;
    }

    void bindParams(uint32_t slot) const {
        gl::bindRange(GL_UNIFORM_BUFFER, bindings_.params, params_.id(), static_cast<GLintptr>(size_t(slot) * param_stride_),
                          sizeof(SbsParams));
    }

    /// Deferred pairs, after `pass` drew with the deferring program: the pairs it appended worked by
    /// the compute pass, and the fragments past the pairs buffer by its per-fragment program (group
    /// counts written on the GPU: nothing read back), or, when it overflowed the fragments buffer
    /// or the triangle slots, `pass` drawn again with the fragment-stage program under predicates
    /// that hold only then (and the compute passes given nothing).
    template <class Pass>
    void workDeferredPairs(const Pass& pass, const BufferRange& masks, const BufferRange& lut_table, const SbsFrameBuffers& frame) {
        if (options_.deferred_pairs == 0) return;
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        // The regions the geometry stage handed over instead of drawing them: their pairs appended
        // as the fragment stage's were, before the pairs' group counts are taken.
        if (light_coverage_.id() != 0) coverageItems();
        deferral_args_.use();
        glDispatchCompute(1, 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
        light_compute_.use();
        bindParams(0);  // the compute pass takes each pair's list block and flags from its triangle slot
        glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, deferral_.id());
        glDispatchComputeIndirect(static_cast<GLintptr>(PENUMBRA_SBS_DEFERRAL_ARGS * 4));
        light_fragments_.use();  // no groups unless the pairs buffer filled up
        glDispatchComputeIndirect(static_cast<GLintptr>(PENUMBRA_SBS_DEFERRAL_FRAGMENT_ARGS * 4));
        // The pairs handed to the tables pass, then every exact test handed on by any.
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        table_args_.use();
        glDispatchCompute(1, 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
        light_tables_.use();
        glDispatchComputeIndirect(static_cast<GLintptr>(PENUMBRA_SBS_DEFERRAL_SAMPLE_ARGS * 4));
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        test_args_.use();
        glDispatchCompute(1, 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
        light_tests_.use();
        glDispatchComputeIndirect(static_cast<GLintptr>(PENUMBRA_SBS_DEFERRAL_TEST_ARGS * 4));
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        // The redraw's predicates: list block b needed and the draws overflowed (the header's binding
        // is by default the work counters'; the light pass's bindings are made again after).
        glDisable(GL_STENCIL_TEST);
        fallback_blocks_.use();
        glBindVertexArray(empty_vao_.id());
        gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.header, lists_.header.id(), 0, sizeof(SampleListsHeader));
        gl::drawListBlockPredicates(fallback_queries_, options_.max_list_blocks, options_.grid_width, options_.grid_height);
        bindLightPass(masks, lut_table, frame);
        pass(light_fragment_, fallback_queries_);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }

    /// Once per frame after the lists (coverage): the occupancy bits and each tile's longest list.
    void coverageBits() {
        const uint32_t zero = 0;
        glClearNamedBufferSubData(triangles_.id(), GL_R32UI, static_cast<GLintptr>((tile_base_ + 4ull * regions_) * 4),
                                  static_cast<GLsizeiptr>(grid_tiles_ * 4), GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        coverage_bits_.use();
        bindParams(0);
        glDispatchCompute(coverage_bit_groups_, 1, 1);  // <= 8192 * 256 / 64 groups
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }

    /// One workgroup, or (`rounds`) the groups the region args program wrote for this run of the
    /// deferred passes: none when nothing waits for it (the GL_DISPATCH_INDIRECT_BUFFER is bound).
    static void roundDispatch(bool rounds) {
        if (rounds) {
            glDispatchComputeIndirect(static_cast<GLintptr>(PENUMBRA_SBS_DEFERRAL_ROUND_ARGS * 4));
        } else {
            glDispatchCompute(1, 1, 1);
        }
    }

    /// The coverage pass over the records appended since its last run: their tile counts, the
    /// counts' scan into first items, the items' group counts, then the items (all sized on the
    /// GPU by the records appended). `rounds` (the compute light pass): the region args program
    /// also decides whether anything waits for this run (PENUMBRA_SBS_DEFERRAL_ROUND_ARGS); the
    /// run's other one-group programs are dispatched with those counts (roundDispatch()).
    void coverageItems(bool rounds = false) {
        glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, deferral_.id());
        region_args_.use();
        glDispatchCompute(1, 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
        coverage_count_.use();
        bindParams(0);
        glDispatchComputeIndirect(static_cast<GLintptr>(PENUMBRA_SBS_DEFERRAL_REGION_ARGS * 4));
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        coverage_scan_.use();
        roundDispatch(rounds);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        item_args_.use();
        roundDispatch(rounds);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
        light_coverage_.use();
        bindParams(0);  // each record's list block and flags come from its triangle slot
        glDispatchComputeIndirect(static_cast<GLintptr>(PENUMBRA_SBS_DEFERRAL_REGION_ARGS * 4));
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }

    /// The light pass's storage buffers (and the compute pass's: the same bindings).
    void bindLightPass(const BufferRange& masks, const BufferRange& lut_table, const SbsFrameBuffers& frame) const {
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.counts, lists_.counts.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.offsets, lists_.offsets.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.positions, lists_.positions.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.ids, lists_.ids.id());
        gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.masks, masks);
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.work, work_.id());
        if (lut_table.empty()) {
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.lut, dummy_.id());
        } else {
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.lut, lut_table);
        }
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.samples, samples_.id());
        if (options_.skips.silhouettes) gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.marks, marks_.id());
        if (options_.skips.closed_casters) gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.near_samples, near_.id());
        if (options_.deferred_pairs > 0) {
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.deferral, deferral_.id());
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.pairs, pairs_.id());
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.triangles, triangles_.id());
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.tests, tests_.id());
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.table_pairs, table_pairs_.id());
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.fragments, fragments_.id());
        }
        if (!frame.sets.empty()) {
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.sets, frame.sets);
        } else {
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.sets, dummy_.id());
        }
    }

    /// workDeferredCompute's window of a run that no windows follow (its overflow is worked inline).
    static constexpr uint32_t kNoWindows = 0xFFFFFFFFu;
    /// SoftLightPass::Compute, after the deferred passes' setup of the triangles dispatched since the
    /// last call: the coverage pass appends their regions' pairs, the pairs, fragments, tables and
    /// exact-test passes work them, and when the pairs and fragments overflowed the coverage pass's
    /// inline program works every region itself instead (group counts decided on the GPU).
    /// `window`: 0 a run that windows follow, k + 1 window k of the last run, kNoWindows a run
    /// none follow.
    void workDeferredCompute(uint32_t window) {
        if (options_.overflow_windows > 0)  // light_pass_args.comp.glsl's penumbraSbsWindow
            for (const gl::Program* program : {&region_args_, &coverage_count_, &deferral_args_})
                glProgramUniform1ui(program->id(), 0, window);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.work, work_.id());  // the setup bound the header there
        coverageItems(true);
        const auto args = [&](const gl::Program& program) {
            program.use();
            roundDispatch(true);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
        };
        const auto indirect = [&](const gl::Program& program, uint32_t words) {
            program.use();
            bindParams(0);  // each entry's list block and flags come from its triangle slot
            glDispatchComputeIndirect(static_cast<GLintptr>(words * 4));
        };
        args(deferral_args_);
        indirect(light_compute_, PENUMBRA_SBS_DEFERRAL_ARGS);
        indirect(light_fragments_, PENUMBRA_SBS_DEFERRAL_FRAGMENT_ARGS);  // no groups unless the pairs filled up
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        args(inline_args_);
        indirect(light_inline_, PENUMBRA_SBS_DEFERRAL_INLINE_ARGS);  // no groups unless the fragments overflowed too
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        args(table_args_);
        indirect(light_tables_, PENUMBRA_SBS_DEFERRAL_SAMPLE_ARGS);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        args(test_args_);
        indirect(light_tests_, PENUMBRA_SBS_DEFERRAL_TEST_ARGS);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }

    /// The windows a run of at most `records` (triangle, list block) records may split into: none
    /// when its pairs cannot fill the pairs buffer (a record pairs with each view sample at most
    /// once) or its fragments the fragments buffer; else as many as its fragments could fill the
    /// fragments buffer, plus one, at most overflow_windows. The GPU's split
    /// (light_pass_args.comp.glsl) never exceeds this: the windows not issued would find no work.
    uint32_t runWindows(uint64_t records) const {
        const uint64_t samples = std::max<uint32_t>(setup_.sample_count, 1);
        if (records * samples <= options_.deferred_pairs) return 0;
        const uint64_t fragments = records * std::min<uint64_t>(samples, uint64_t(options_.grid_width) * options_.grid_height);
        if (fragments <= fragment_capacity_) return 0;
        return static_cast<uint32_t>(std::min<uint64_t>(options_.overflow_windows, detail::divUp(fragments, fragment_capacity_) + 1));
    }

    /// A run of the deferred passes over at most `records` records, then its windows (nothing to
    /// do unless the run overflowed). Windows follow only runs that hold list block 0 (`block0`:
    /// every listed texel's), not those of later blocks only, which are idle unless lists are long:
    /// their overflow, if any, is worked inline.
    void workDeferredRun(uint64_t records, bool block0) {
        const uint32_t windows = block0 ? runWindows(records) : 0u;
        workDeferredCompute(windows > 0 ? 0u : kNoWindows);
        for (uint32_t k = 0; k < windows; ++k) workDeferredCompute(k + 1);
    }

    /// SoftLightPass::Compute's light pass: per list block and class the setup of every range
    /// (blocks no list reaches return on the GPU), the deferred passes whenever the triangles
    /// dispatched since their last run could fill the slots, then SoftSkips::closed_casters'
    /// second pass the same way.
    void computeLightPass(const CasterBuffer* casters, uint32_t caster_count) {
        coverageBits();
        // (triangle, list block) pairs between two runs of the deferred passes: at most the slots,
        // and the coverage pass's items below 2^31 (a region spans at most every tile of the grid);
        // triangles per dispatch at most 65 535 groups (GL's minimum).
        const uint64_t run_pairs = std::max<uint64_t>(1, std::min<uint64_t>(slots_, (1ull << 31) / grid_tiles_));
        const uint32_t chunk = static_cast<uint32_t>(std::min<uint64_t>(run_pairs, 65535u * PENUMBRA_SBS_SETUP_GROUP));
        uint64_t pending = 0;  // pairs dispatched at most since the deferred passes last ran
        bool pending_block0 = false;  // ... of which some of list block 0
        const GLuint setup_id = setup_program_.id(), gate_id = setup_gate_.id();
        // One range of class slot `c` (0 closed, 1 open, 2 the closed casters' second pass): per
        // chunk of triangles, runs of list blocks (as many as the slots hold beside the chunk),
        // each dispatched for the blocks the GPU finds needed (the gate).
        const auto setup = [&](const CasterBuffer& range, uint32_t c) {
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.caster_positions, range.positions);
            if (range.indices.empty()) {
                gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.caster_indices, dummy_.id());
            } else {
                gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.caster_indices, range.indices);
            }
            glProgramUniform1ui(setup_id, 1, static_cast<GLuint>(std::min<uint64_t>(range.positions.size / 4, 0xFFFFFFFFu)));
            for (uint32_t first = 0; first < range.triangles; first += chunk) {
                const uint32_t n = std::min(chunk, range.triangles - first);
                const uint32_t blocks = static_cast<uint32_t>(std::clamp<uint64_t>(run_pairs / n, 1, options_.max_list_blocks));
                glProgramUniform4ui(setup_id, 0, first, n, range.stride / 4, range.indices.empty() ? 0u : 1u);
                glProgramUniform4ui(gate_id, 0, first, n, range.stride / 4, range.indices.empty() ? 0u : 1u);
                for (uint32_t b0 = 0; b0 < options_.max_list_blocks; b0 += blocks) {
                    const uint32_t run = std::min(blocks, options_.max_list_blocks - b0);
                    if (pending + uint64_t(n) * run > run_pairs) {
                        workDeferredRun(pending, pending_block0);
                        pending = 0;
                        pending_block0 = false;
                    }
                    pending_block0 |= b0 == 0;
                    bindParams(1 + kSlotsPerBlock * b0 + c);
                    gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.header, lists_.header.id(), 0, sizeof(SampleListsHeader));
                    setup_gate_.use();
                    glProgramUniform1ui(gate_id, 2, run);
                    glDispatchCompute(1, 1, 1);
                    glMemoryBarrier(GL_COMMAND_BARRIER_BIT);
                    setup_program_.use();
                    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, deferral_.id());
                    glDispatchComputeIndirect(static_cast<GLintptr>(PENUMBRA_SBS_DEFERRAL_SETUP_ARGS * 4));
                    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);  // the next gate rewrites the arguments
                    pending += uint64_t(n) * run;
                }
            }
        };
        const auto pass = [&](bool culled) {
            for (uint32_t k = 0; k < (culled ? 1u : 2u); ++k) {
                const CasterClass cls = k == 0 ? CasterClass::Closed : CasterClass::Open;
                for (uint32_t i = 0; i < caster_count; ++i)
                    if (casters[i].triangles > 0 && casters[i].caster_class == cls) setup(casters[i], culled ? 2 : k);
            }
            workDeferredRun(pending, pending_block0);
            pending = 0;
            pending_block0 = false;
        };
        pass(false);
        if (options_.skips.closed_casters) pass(true);
    }

    void lightPassAndResolve(const BufferRange& lut_table, const DrawCasters& draw_casters, const SbsFrameBuffers& frame,
                             const CasterBuffer* casters = nullptr, uint32_t caster_count = 0) {
        const bool has_sets = !frame.sets.empty();
        const LightLutSetup* lut = has_lut_ ? &lut_ : nullptr;
        // Slot 0: the predicate pass and the resolve; 1 + 6 b + c: list block b, c = 0 closed, 1 open,
        // 2 closed again (SoftSkips::closed_casters' second pass), and for count_work's complement
        // draws (no triangle slot taken, no region handed to the coverage pass, no culled triangle
        // counted twice) 3 closed, 4 open, 5 the second pass.
        for (uint32_t slot = 0; slot <= kSlotsPerBlock * options_.max_list_blocks; ++slot) {
            const uint32_t block = slot == 0 ? 0u : (slot - 1) / kSlotsPerBlock;
            const uint32_t c = slot == 0 ? 1u : (slot - 1) % kSlotsPerBlock;
            // Validated at construction: cannot throw.
            SbsParams p = sampleBasedSoftParams(options_, sets_, lut, setup_.sample_count, block, has_sets, c != 1 && c != 4,
                                                c == 2 || c == 5);
            p.epsilon.w = sample_reach_;  // SoftSkips::wedges: the sample table's own sphere (tighter)
            if (c >= 3) p.reserved.y |= PENUMBRA_SBS_FLAG_COMPLEMENT;
            std::memcpy(params_staging_.data() + size_t(slot) * param_stride_, &p, sizeof p);
        }
        glNamedBufferSubData(params_.id(), 0, static_cast<GLsizeiptr>(params_staging_.size()), params_staging_.data());
        const uint32_t zero = 0;
        const BufferRange masks = frame.masks.empty() ? this->masks() : frame.masks;
        const uint64_t mask_bytes = uint64_t(std::max<uint32_t>(setup_.sample_count, 1)) * words_ * 4;
        glClearNamedBufferSubData(masks.buffer, GL_R32UI, static_cast<GLintptr>(masks.offset),
                                  static_cast<GLsizeiptr>(std::min<uint64_t>(mask_bytes, masks.size)), GL_RED_INTEGER,
                                  GL_UNSIGNED_INT, &zero);
        glClearNamedBufferSubData(work_.id(), GL_R32UI, 0, PENUMBRA_SBS_WORK_WORDS * 4, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
        if (options_.deferred_pairs > 0)
            glClearNamedBufferSubData(deferral_.id(), GL_R32UI, 0, PENUMBRA_SBS_DEFERRAL_WORDS * 4, GL_RED_INTEGER, GL_UNSIGNED_INT,
                                      &zero);
        if (options_.skips.closed_casters)
            glClearNamedBufferSubData(near_.id(), GL_R32UI, 0,
                                      static_cast<GLsizeiptr>((size_t(setup_.sample_count) +
                                                               size_t(options_.grid_width) * options_.grid_height) * 4),
                                      GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        if (options_.light_pass == SoftLightPass::Compute) {
            if (!timers_.empty()) timers_[1].begin();
            gl::bindBase(GL_UNIFORM_BUFFER, bindings_.influence, influence_params_.id());
            bindLightPass(masks, lut_table, frame);
            computeLightPass(casters, caster_count);
        } else {
            glBindFramebuffer(GL_DRAW_FRAMEBUFFER, framebuffer_.id());
            glViewport(0, 0, static_cast<GLsizei>(options_.grid_width), static_cast<GLsizei>(options_.grid_height));
            glDisable(GL_DEPTH_TEST);
            glDisable(GL_CULL_FACE);
            glDisable(GL_RASTERIZER_DISCARD);
            glDisable(GL_STENCIL_TEST);  // the occupancy stencil's own state comes at (2c)
            gl::setPassRasterState();
            if (!timers_.empty()) timers_[1].begin();
            // (2) Which list blocks does the longest list need? One point per block, on the GPU.
            blocks_.use();
            glBindVertexArray(empty_vao_.id());
            bindParams(0);
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.header, lists_.header.id(), 0, sizeof(SampleListsHeader));
            gl::drawListBlockPredicates(block_queries_, options_.max_list_blocks, options_.grid_width, options_.grid_height);
            // (2b) SoftSkips::silhouettes: mark the texels of every potential silhouette's region.
            if (options_.skips.silhouettes) {
                glClearNamedBufferSubData(marks_.id(), GL_R32UI, 0, static_cast<GLsizeiptr>(marks_.size()), GL_RED_INTEGER,
                                          GL_UNSIGNED_INT, &zero);
                glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
                silhouettes_.use();
                bindParams(0);
                gl::bindBase(GL_UNIFORM_BUFFER, bindings_.influence, influence_params_.id());
                gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.marks, marks_.id());
                (*draw_adjacency_)();
                glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
                // ... and the texels of view samples for which the oracle's coplanar rule opens a
                // triangle's edges (SoftSkips::silhouettes' second condition): every triangle's region.
                silhouettes_near_.use();
                bindParams(0);
                gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.counts, lists_.counts.id());
                gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.offsets, lists_.offsets.id());
                gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.positions, lists_.positions.id());
                (*draw_adjacency_)();
                glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            }
            // (2c) SoftSkips::empty_blocks: the stencil counts each texel's non-empty list blocks.
            const bool stencil = options_.skips.empty_blocks;
            const uint32_t stencil_blocks = std::min(options_.max_list_blocks, gl::kOccupancyStencilBlocks);
            if (stencil) {
                gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.counts, lists_.counts.id());
                gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.offsets, lists_.offsets.id());
                gl::drawOccupancyStencil(framebuffer_.id(), occupancy_.id(), empty_vao_.id(), block_queries_, options_.max_list_blocks,
                                         [&](uint32_t b) { bindParams(1 + kSlotsPerBlock * b + 1); });
            }
            // (3) Light pass, block by block; blocks no list needs are skipped by the GPU. With the
            // stencil, block b's fragments are shaded where b < the texel's non-empty blocks (early
            // fragment tests); count_work draws the rest too, so fragments_skipped counts them.
            const auto stencilTest = [&](uint32_t b, GLenum func) { gl::occupancyStencilTest(stencil, b, func); };
            gl::bindBase(GL_UNIFORM_BUFFER, bindings_.influence, influence_params_.id());
            bindLightPass(masks, lut_table, frame);
            if (coverage_bits_.id() != 0) {
                // coverage_texels: the occupancy bits the coverage pass reads (the lists are done).
                coverageBits();
            }
            light_pass_.use();
            const bool complement = stencil && options_.count_work;
            // The first pass: every list block, closed then open casters (and count_work's complement).
            const auto first_pass = [&](const gl::Program& program, const std::vector<gl::OcclusionQuery>& queries) {
                for (uint32_t b = 0; b < options_.max_list_blocks; ++b) {
                    glBeginConditionalRender(queries[b].id(), GL_QUERY_WAIT);
                    stencilTest(b, GL_LESS);
                    for (uint32_t c = 0; c < 2; ++c) {
                        bindParams(1 + kSlotsPerBlock * b + c);
                        program.use();
                        draw_casters(c == 0 ? CasterClass::Closed : CasterClass::Open);
                    }
                    if (complement && b < stencil_blocks) {
                        stencilTest(b, GL_GEQUAL);
                        for (uint32_t c = 0; c < 2; ++c) {
                            bindParams(1 + kSlotsPerBlock * b + (c == 0 ? 3 : 4));
                            program.use();
                            draw_casters(c == 0 ? CasterClass::Closed : CasterClass::Open);
                        }
                    }
                    glEndConditionalRender();
                }
            };
            // SoftSkips::closed_casters' second pass: the culled triangles, for the samples the first
            // pass flagged near a kept closed one.
            const auto culled_pass = [&](const gl::Program& program, const std::vector<gl::OcclusionQuery>& queries) {
                for (uint32_t b = 0; b < options_.max_list_blocks; ++b) {
                    glBeginConditionalRender(queries[b].id(), GL_QUERY_WAIT);
                    for (GLenum func : {GLenum(GL_LESS), GLenum(GL_GEQUAL)}) {
                        if (func == GL_GEQUAL && !(complement && b < stencil_blocks)) continue;
                        stencilTest(b, func);
                        bindParams(1 + kSlotsPerBlock * b + (func == GL_GEQUAL ? 5 : 2));
                        program.use();
                        draw_casters(CasterClass::Closed);
                    }
                    glEndConditionalRender();
                }
            };
            first_pass(light_pass_, block_queries_);
            workDeferredPairs(first_pass, masks, lut_table, frame);
            if (options_.skips.closed_casters) {
                glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);  // the first pass's near flags
                if (stencil) {
                    // The occupancy stencil drops to 0 on the texels without a flagged sample: the
                    // second pass's fragments there would only return (light_pass.frag.glsl).
                    near_stencil_.use();
                    glBindVertexArray(empty_vao_.id());
                    bindParams(1 + 2);
                    glEnable(GL_STENCIL_TEST);
                    glStencilMask(0xFFu);
                    glStencilFunc(GL_ALWAYS, 0, 0xFFu);
                    glStencilOp(GL_KEEP, GL_KEEP, GL_ZERO);
                    glDrawArrays(GL_TRIANGLES, 0, 3);
                    glStencilMask(0u);
                    glStencilOp(GL_KEEP, GL_KEEP, GL_KEEP);
                }
                // Its predicates (count_work draws it whole, counting its fragments): list block b holds
                // a flagged sample somewhere. Usually none does, and the pass draws nothing.
                if (!options_.count_work) {
                    glDisable(GL_STENCIL_TEST);
                    near_blocks_.use();
                    glBindVertexArray(empty_vao_.id());
                    for (uint32_t b = 0; b < options_.max_list_blocks; ++b) {
                        glBeginConditionalRender(block_queries_[b].id(), GL_QUERY_WAIT);
                        glBeginQuery(GL_ANY_SAMPLES_PASSED, near_queries_[b].id());
                        bindParams(1 + kSlotsPerBlock * b + 2);
                        glDrawArrays(GL_TRIANGLES, 0, 3);
                        glEndQuery(GL_ANY_SAMPLES_PASSED);
                        glEndConditionalRender();
                    }
                }
                culled_pass(light_pass_, options_.count_work ? block_queries_ : near_queries_);
                workDeferredPairs(culled_pass, masks, lut_table, frame);
            }
            glDisable(GL_STENCIL_TEST);
        }
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        if (!timers_.empty()) timers_[1].end();
        // (4) Resolve.
        if (!timers_.empty()) timers_[2].begin();
        resolve_.use();
        bindParams(0);
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.slots, lists_.slots.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.texels, lists_.texels.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.resolve_offsets, lists_.offsets.id());
        gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.masks, masks);
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.work, work_.id());
        if (frame.visibility.empty()) {
            gl::bindBase(GL_SHADER_STORAGE_BUFFER, bindings_.visibility, visibility_.id());
        } else {
            gl::bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.visibility, frame.visibility);
        }
        const detail::DispatchGrid grid = detail::foldDispatch(detail::divUp(setup_.sample_count, 256));
        if (grid.groups) glDispatchCompute(grid.x, grid.y, 1);
        if (!timers_.empty()) timers_[2].end();
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    }
};

}  // namespace penumbra

#endif
