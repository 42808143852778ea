// soft_shadows — penumbra's main job: render a scene lit by a spherical light with sample-based
// soft shadows and write a PNG, optionally with a one-line JSON report on stdout.
//
//   soft_shadows [--scene builtin:torus_knot|builtin:columns|builtin:hairball|builtin:grass|builtin:window_wall|PATH.obj]
//                [--light-pos x,y,z] [--light-radius r] [--samples N] [--width W] [--height H]
//                [--mode reference|soft|hard|hpc|dsm|volumetric] [--reference] [--out FILE.png] [--json] [--no-ground]
//                [--view-samples depth|exact] [--lut exact|lut|brute] [--lut-res R] [--sets K] [--rotations R] [--grid G]
//                [--opacity A] [--dsm-res R] [--dsm-samples S] [--tolerance E]
//                [--aa off|edge|full] [--aa-samples 4|8|16] [--aa-stencil provable|chebyshev|chebyshev-inner]
//                [--fog SIGMA_S,SIGMA_T] [--sm-res R] [--tessellation adaptive|static]
//
// Modes
//   reference (default): every view sample's visibility of N light samples from the exact
//       double-precision oracle (penumbra/reference/visibility.hpp) on the CPU: soft shadows.
//   soft: the GPU sample-based soft-shadow pipeline (penumbra/gl/pipelines/sample_based_soft.hpp,
//       sintorn2008 §4): G-buffer or depth-buffer view samples, K sets of N light samples chosen
//       per pixel, the light-sample LUT generated on the GPU, influence regions, resolve;
//       --reference compares every bit with the oracle on the same float view samples and the
//       same light samples (JSON reference.mismatched_bits, total_bits, ties, visibility_rmse;
//       depth view samples: the positions the GPU reconstructed, read back from its lists,
//       reference.gpu_reconstruction_differs of them differing from the CPU twin's) and
//       writes <out>_reference.png (the oracle's image) and <out>_error.png (|error| heat map).
//       --frames F runs the pipeline F times, every pixel with a fresh selection word each frame,
//       and writes the running average (JSON temporal.*: RMSE against an oracle image per frame).
//   hpc: hierarchical penumbra casting on the CPU (penumbra/penumbra_casting.hpp, laine2005): the
//       same primary-ray view samples as reference mode, a spherical light with K = --sets (8)
//       sets of N samples chosen per pixel (lightSampleSet), every triangle streamed once;
//       --reference compares every bit with the oracle on the same light samples (JSON
//       reference.mismatched_bits, total_bits, ties).
//   hard: the GPU alias-free hard-shadow pipeline (penumbra/pipelines/alias_free_hard.hpp,
//       sintorn2008 §3) from the light's centre, on a headless GL context (PENUMBRA_GL=egl|osmesa);
//       --reference adds the oracle's verdict for the same samples and light point to the JSON
//       (mismatched, ties, samples).
//       --aa edge|full: eye-view anti-aliasing (penumbra/gl/shadow_edge_stencil.hpp, galoppo2010):
//       N (--aa-samples, 4) rotated-grid sub-samples on each pixel's plane, tested by the same
//       pipeline where the shadow-edge stencil (--aa-stencil: provable, or galoppo2010's Chebyshev
//       test over a conservative moment map, or chebyshev-inner: that test with its "fully shadowed"
//       claim proven by inner coverage) flags the pixel (edge) or everywhere (full), resolved
//       to a lit fraction per pixel. Off, edge and full all run; the image is --aa's, and
//       <out>_aa_compare.png (off | edge | full) and <out>_aa_stencil.png (flagged pixels red,
//       with --reference missed edge pixels green) are written beside it. --reference: the oracle
//       on every centre and sub-sample the GPU tested (JSON reference.missed_edge_pixels: pixels
//       whose points disagree that the stencil left single-sampled, for every stencil) and on 64
//       points per pixel (reference.rmse of --aa's mode, aa.rmse of off / edge / full).
//   dsm: deep shadow maps (penumbra/deep_shadow_map.hpp, lokovic2000) of semi-transparent casters:
//       every mesh but the ground casts with opacity --opacity (A, default 0.5), every mesh
//       receives. The light is the scene's light as a point: a perspective view from its centre
//       toward the centre of the casters' bounds, the frustum fitted to their bounding sphere
//       (fitDsmLight). An R x R map (--dsm-res, 256) of S sub-samples per texel (--dsm-samples,
//       16) compressed to --tolerance (0: 1 / (2 S)), built on the CPU twin (buildDeepShadowMap:
//       the one place the GPU build will replace); each primary hit gets the bilinear lookup at its
//       light depth minus a depth bias (kDsmBiasTexels) times the direct light. --reference
//       compares every receiver with the exact transmittance to the light's centre
//       (penumbra/reference/transmittance.hpp; JSON reference.rmse, max_error, compared, ties).
//   volumetric: light shafts in fog (billeter2010 light volumes): a spot light at the scene's light
//       framing the casters, its R x R shadow map (--sm-res, 1024) tessellated into a closed light
//       volume on the GPU (--tessellation adaptive: quadtree, flatness 1e-6; static: 2 R^2
//       triangles) and drawn over the camera's depth, each crossing adding or subtracting the
//       airlight of a homogeneous medium (--fog SIGMA_S,SIGMA_T; isotropic, sun2005's closed form
//       as a table) clamped to the scene; writes <out> and <out>_airlight.png. --reference: the
//       ray march of the same shadow map (512 steps, every pixel; JSON reference.rmse) and with
//       exact visibility (256 steps, every 4th pixel each way; reference.rmse_oracle).
//
// Before any work: the arguments are parsed (CLI11) and checked (checkArgs: values, which flags
// the mode uses, the output path: extension .png, folder writable) and the memory the image
// sizes need against the machine's (checkMemory). After loading the scene and before allocating
// anything large: the light against the scene's bounds (checkLight; --mode dsm: against the
// casters' bounding sphere, fitDsmLight) and the memory estimate again, with the scene's
// triangles. Long phases print their progress on stderr (Progress). Exit codes: 0 done (and
// --help), 1 failed while running or a requested check found a difference (checksVerdict),
// 2 bad arguments or a run that cannot work.
//
// Adding a flag: a field in Args, one add_option line in addOptions(), its row in kModeFlags
// (which modes use it) and its value checks in checkArgs(). Vector-valued flags parse with
// parseVec3 (as --light-pos does).
// First: transmittance.hpp names penumbra::detail as `detail::` from inside penumbra::reference, which
// resolves to penumbra::reference::detail once reference/compare.hpp (included by the pipelines) has
// declared it, and then fails to compile; included before it, its names bind to penumbra::detail.
#include <penumbra/reference/transmittance.hpp>

#include <penumbra/bent_normals.hpp>
#include <penumbra/deep_shadow_map.hpp>
#include <penumbra/gl/deep_shadow_map.hpp>
#include <penumbra/gl/headless.hpp>
#include <penumbra/gl/light_lut.hpp>
#include <penumbra/gl/light_volume.hpp>
#include <penumbra/gl/pipelines/alias_free_hard.hpp>
#include <penumbra/gl/pipelines/sample_based_soft.hpp>
#include <penumbra/gl/shadow_edge_stencil.hpp>
#include <penumbra/light_samples.hpp>
#include <penumbra/penumbra_casting.hpp>
#include <penumbra/reference/compare.hpp>
#include <penumbra/reference/light_shafts.hpp>
#include <penumbra/reference/light_samples.hpp>
#include <penumbra/reference/visibility.hpp>
#include <penumbra/scene/gl_scene.hpp>
#include <penumbra/scene/image.hpp>
#include <penumbra/scene/obj.hpp>
#include <penumbra/scene/scene.hpp>
#include <penumbra/version.hpp>

#include <CLI/CLI.hpp>
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;  // keys in insertion order, as the report always had them

// =============================================================================================
// Command line

struct Args {
    std::string scene = "builtin:torus_knot";
    std::string mode = "reference";
    std::string out = "soft_shadows.png";
    bool has_light_pos = false;
    glm::dvec3 light_pos{0.0};
    double light_radius = -1.0;  // < 0: the scene's default
    uint32_t samples = 64;
    uint32_t width = 512, height = 384;
    bool json = false;
    bool ground = true;
    bool reference = false;
    std::string view_samples = "depth";  // hard mode: depth (reconstructed from the depth buffer) | exact
    glm::dvec3 origin{0.0};              // the whole scene translated by this (double) offset
    std::string shading = "bent";        // direct light: bent (sintorn2008 §4.3) | phong
    bool compare_shading = false;        // also write <out stem>_shading.png: Phong | bent
    uint32_t frames = 1;                 // reference and soft modes: temporal accumulation over F frames
    uint32_t frames_reference = 4096;    // ... against an oracle image with this many samples
    std::string lut = "exact";           // soft mode: exact | lut | brute (penumbra::SoftMode)
    uint32_t lut_res = 64;               // soft mode: LUT resolution R (R x R x R texels per table)
    uint32_t sets = 4;                   // soft mode: K light-sample sets, chosen per pixel
    uint32_t rotations = 8;              // soft mode: R rotation steps about the light's axis, per pixel
    uint32_t grid = 256;                 // soft mode: light grid G x G (lists and influence regions)
    std::string skips = "all";           // hard and soft modes: the work skips on (all | none | a,b,...)
    std::vector<std::string> skip_list;  // ... as names (kSoftSkips / kHardSkips)
    bool check_skips = false;            // also run with every skip off and compare bit for bit
    double opacity = 0.5;                // dsm mode: opacity of every caster (fraction of light it stops)
    uint32_t dsm_res = 256;              // dsm mode: R, the map is R x R texels
    uint32_t dsm_samples = 16;           // dsm mode: S jittered sub-samples per texel
    double tolerance = 0.0;              // dsm mode: compression tolerance (L-infinity); 0 = 1 / (2 S)
    std::string dsm_build = "gpu";       // dsm mode: gpu (penumbra/gl/deep_shadow_map.hpp) or cpu (its twin)
    std::string aa = "off";              // hard mode: eye-view anti-aliasing (galoppo2010): off | edge | full
    uint32_t aa_samples = 4;             // ... N sub-samples per multi-sampled pixel: 4 | 8 | 16 (rotated grid)
    std::string aa_stencil = "provable"; // ... which stencil picks the pixels of --aa edge: provable | chebyshev | chebyshev-inner
    double fog_sigma_s = 0.05, fog_sigma_t = 0.08;  // volumetric mode: the medium (scattering, extinction)
    uint32_t sm_res = 1024;              // volumetric mode: the spot light's shadow map, R x R
    std::string tessellation = "adaptive";  // volumetric mode: adaptive | static light-volume tessellation
    bool skip(const char* name) const { return std::find(skip_list.begin(), skip_list.end(), name) != skip_list.end(); }
};

// The skips each mode can switch (--skips), in their report order. Each leaves every shadow bit
// as it is; --check-skips proves it on the frame at hand.
//   soft: empty = light-pass fragments of empty list blocks return at once (SoftSkips::empty_blocks);
//         cull  = closed casters' triangles that face away from the whole light are culled
//                 (SoftSkips::closed_casters); cut = the supporting-plane cut, per pair
//                 (SoftSkips::plane_cut) and of the influence regions (cut_by_supporting_plane);
//         fit   = the light grid fitted to the view samples (sintorn2008 §4.3) instead of their box;
//         silhouette = outside every potential silhouette edge's region one test from the light
//                 centre per pair (SoftSkips::silhouettes, laine2005 §3.3);
//         wedge = view samples beyond one of a caster's wedge planes (its edges' planes tangent
//                 to the light, its own plane) get no pair (SoftSkips::wedges).
//   hard: cull  = light_facing_only; fit = fit_frustum; shadowed = skip_shadowed; box = clip_to_box;
//         empty = skip_empty_texels (an occupancy stencil culls the fragments of sample-less texels).
const std::vector<std::string> kSoftSkips = {"empty", "cull", "cut", "fit", "silhouette", "wedge"};
const std::vector<std::string> kHardSkips = {"cull", "fit", "shadowed", "box", "empty"};

/// The flags' text as given, before checkArgs turns them into Args values.
struct RawArgs {
    std::string light_pos, light_radius, samples = "64", width = "512", height = "384", origin;
    std::string frames = "1", frames_reference = "4096";
    std::string lut_res = "64", sets = "4", grid = "256", rotations = "8";
    std::string opacity = "0.5", dsm_res = "256", dsm_samples = "16", tolerance = "0";
    std::string aa_samples = "4";
    std::string fog = "0.05,0.08", sm_res = "1024";
    bool no_ground = false;
};

/// A usage problem: reported as "soft_shadows: <what>" with exit code 2.
struct UsageError {
    std::string what;
};

template <typename... Parts>
[[noreturn]] void usageError(const Parts&... parts) {
    std::ostringstream out;
    (out << ... << parts);
    throw UsageError{out.str()};
}

/// Which modes use a flag; a flag given to a mode that would ignore it is an error.
struct ModeFlag {
    const char* flag;
    bool reference;  // used by --mode reference
    bool hard;       // used by --mode hard
    bool soft;       // used by --mode soft
    bool hpc;        // used by --mode hpc
    bool dsm;        // used by --mode dsm
    const char* why_not;
    const char* dsm_why_not = nullptr;  // the reason given to --mode dsm, when why_not does not fit it
    bool volumetric = false;            // used by --mode volumetric
};
const char* const kVolumetricOnly = "only --mode volumetric renders light shafts";
const char* const kVolumetricWhyNot = "light shafts come from a spot light at the scene's light, a point, and its shadow map";
// --reference in hard mode checks the GPU against the oracle at the light's centre only, so it
// uses neither the light samples nor the radius. --mode dsm sees the light as a point too.
const char* const kDsmPointLight = "a deep shadow map sees the light as a point, its centre";
const char* const kDsmOnly = "only --mode dsm builds a deep shadow map of semi-transparent casters";
const char* const kAaOnly = "only --mode hard anti-aliases its shadows with extra sub-samples per pixel";
const ModeFlag kModeFlags[] = {
    {"--samples", true, false, true, true, false, "hard shadows use one light point, the light's centre",
     "a deep shadow map takes its sub-samples per texel from --dsm-samples"},
    {"--light-radius", true, false, true, true, false, "hard shadows use one light point, the light's centre", kDsmPointLight},
    {"--reference", false, true, true, true, true, "reference mode is the oracle already", nullptr, true},
    {"--view-samples", false, true, true, false, false, "reference, hpc and dsm modes trace exact primary rays on the CPU"},
    {"--frames", true, false, true, false, false, "hard shadows use one light point: there is nothing to accumulate; hpc renders one frame",
     "a deep shadow map is one deterministic frame"},
    {"--frames-reference", true, false, true, false, false, "hard shadows use one light point: there is nothing to accumulate; hpc renders one frame",
     "a deep shadow map is one deterministic frame"},
    {"--lut", false, false, true, false, false, "only the GPU soft-shadow pipeline looks light samples up in a LUT"},
    {"--lut-res", false, false, true, false, false, "only the GPU soft-shadow pipeline looks light samples up in a LUT"},
    {"--sets", false, false, true, true, false, "only the soft and hpc modes choose light-sample sets per pixel"},
    {"--rotations", false, false, true, false, false, "only the GPU soft-shadow pipeline rotates light samples per pixel"},
    {"--grid", false, false, true, false, false, "only the GPU soft-shadow pipeline has a separate light grid"},
    {"--skips", false, true, true, false, false, "the oracle does every test; penumbra casting has no skip switches here",
     "the deep shadow map has no skip switches"},
    {"--check-skips", false, true, true, false, false, "the oracle does every test; penumbra casting has no skip switches here",
     "the deep shadow map has no skip switches"},
    {"--opacity", false, false, false, false, true, kDsmOnly},
    {"--dsm-res", false, false, false, false, true, kDsmOnly},
    {"--dsm-samples", false, false, false, false, true, kDsmOnly},
    {"--tolerance", false, false, false, false, true, kDsmOnly},
    {"--dsm-build", false, false, false, false, true, kDsmOnly},
    {"--aa", false, true, false, false, false, kAaOnly},
    {"--aa-samples", false, true, false, false, false, kAaOnly},
    {"--aa-stencil", false, true, false, false, false, kAaOnly},
    {"--fog", false, false, false, false, false, kVolumetricOnly, nullptr, true},
    {"--sm-res", false, false, false, false, false, kVolumetricOnly, nullptr, true},
    {"--tessellation", false, false, false, false, false, kVolumetricOnly, nullptr, true},
};

void addOptions(CLI::App& app, Args& a, RawArgs& raw) {
    app.add_option("--scene", a.scene, "builtin:NAME (torus_knot, columns, hairball, grass; window_wall: columns beside a wall with windows, for --mode volumetric) or PATH.obj")
        ->type_name("SCENE")
        ->capture_default_str();
    app.add_option("--light-pos", raw.light_pos, "light centre x,y,z (default: the scene's)")->type_name("X,Y,Z");
    app.add_option("--light-radius", raw.light_radius, "spherical light radius > 0 (default: the scene's); reference and soft modes")
        ->type_name("R");
    app.add_option("--samples", raw.samples,
                   "light samples per view sample: reference mode 1..65536 (default 64); soft mode a multiple of 32 in "
                   "32..1024 (default 128)")
        ->type_name("N");
    app.add_option("--width", raw.width, "image width, 1..16384")->type_name("W")->capture_default_str();
    app.add_option("--height", raw.height, "image height, 1..16384")->type_name("H")->capture_default_str();
    app.add_option("--mode", a.mode,
                   "reference: oracle soft shadows on the CPU; soft: GPU sample-based soft shadows; hpc: hierarchical penumbra "
                   "casting on the CPU; hard: GPU alias-free "
                   "hard shadows; dsm: deep shadow map of semi-transparent casters")
        ->type_name("MODE")
        ->check(CLI::IsMember({"reference", "soft", "hard", "hpc", "dsm", "volumetric"}))
        ->capture_default_str();
    app.add_flag("--reference", a.reference,
                 "hard, soft, hpc and dsm modes: compare with the oracle on the same view samples (and light samples) "
                 "(JSON: reference.*); soft mode also writes <out>_reference.png and <out>_error.png; dsm mode: the "
                 "exact transmittance to the light's centre (reference.rmse, reference.max_error)");
    app.add_option("--out", a.out, "output image (.png); its folder must exist and be writable")
        ->type_name("FILE.png")
        ->capture_default_str();
    app.add_option("--view-samples", a.view_samples,
                   "hard and soft modes: depth = positions reconstructed from the depth buffer (what an engine has), "
                   "exact = the G-buffer's exact surface points")
        ->type_name("depth|exact")
        ->check(CLI::IsMember({"depth", "exact"}))
        ->capture_default_str();
    app.add_option("--origin", raw.origin,
                   "translate scene, camera and light by x,y,z (in double); the GPU works camera-relative")
        ->type_name("X,Y,Z");
    app.add_option("--shading", a.shading,
                   "direct light: bent = sintorn2008 §4.3 bent normals (no light on light-back-facing triangles, "
                   "no leak at the terminator), phong = Lambert with the smooth normals")
        ->type_name("bent|phong")
        ->check(CLI::IsMember({"bent", "phong"}))
        ->capture_default_str();
    app.add_flag("--compare-shading", a.compare_shading,
                 "also write <out>_shading.png beside --out: the same frame with Phong (left) and bent (right)");
    app.add_option("--frames", raw.frames,
                   "reference and soft modes: accumulate F frames (sintorn2008 §4.2 temporal jitter) and report the "
                   "visibility RMSE after every frame against an oracle image (--frames-reference). Reference mode: "
                   "fresh light-sample sets every frame (8 chosen per pixel). Soft mode: the GPU pipeline once per "
                   "frame, every pixel with a fresh set and rotation step (sampleBasedSoftSelection(x, y, frame)); "
                   "writes the running average; with --reference the bit check is on the last frame")
        ->type_name("F")
        ->capture_default_str();
    app.add_option("--frames-reference", raw.frames_reference, "--frames: light samples of the oracle image the RMSE is against")
        ->type_name("N")
        ->capture_default_str();
    app.add_option("--lut", a.lut,
                   "soft mode: exact = certified LUT + exact tests of the bits it cannot vouch for (equals the oracle), "
                   "lut = the seed's LUT approximation, brute = every light sample tested")
        ->type_name("exact|lut|brute")
        ->check(CLI::IsMember({"exact", "lut", "brute"}))
        ->capture_default_str();
    app.add_option("--lut-res", raw.lut_res, "soft mode: LUT resolution R, even, 16..256 (R^3 texels per 128 samples)")
        ->type_name("R")
        ->capture_default_str();
    app.add_option("--sets", raw.sets, "soft mode: K light-sample sets, 1..64, chosen per pixel (neighbours differ for K >= 4)")
        ->type_name("K")
        ->capture_default_str();
    app.add_option("--rotations", raw.rotations,
                   "soft mode: R rotation steps of the light samples about the light's axis, 1..256, one chosen per pixel "
                   "(sintorn2008 §4.2 jitter; 1 = none)")
        ->type_name("R")
        ->capture_default_str();
    app.add_option("--grid", raw.grid, "soft mode: light grid G x G of the sample lists and influence regions, 16..4096")
        ->type_name("G")
        ->capture_default_str();
    app.add_option("--skips", a.skips,
                   "hard and soft modes: the work skips on: all, none, or a comma list; soft: empty (empty list blocks "
                   "return at once), cull (closed casters' triangles facing away from the whole light), cut "
                   "(supporting-plane cut per pair and of the influence regions), fit (light grid fitted to the view "
                   "samples), silhouette (outside every potential silhouette edge's region one test from the light centre), "
                   "wedge (view samples beyond one of a caster's wedge planes get no pair); "
                   "hard: cull, fit, shadowed (no retest of shadowed samples), box (clip to the triangle's "
                   "box), empty (an occupancy stencil culls the fragments of texels with no samples). None changes a "
                   "shadow bit")
        ->type_name("all|none|LIST")
        ->capture_default_str();
    app.add_flag("--check-skips", a.check_skips,
                 "hard and soft modes: also run the frame with every skip off and compare the shadow bits word for "
                 "word (JSON: skips_check.*)");
    app.add_option("--opacity", raw.opacity,
                   "dsm mode: opacity of every caster (every mesh but the ground), in [0, 1]: the fraction of light "
                   "each surface stops")
        ->type_name("A")
        ->capture_default_str();
    app.add_option("--fog", raw.fog,
                   "volumetric mode: the homogeneous medium's scattering and extinction coefficients per world unit, "
                   "0 < SIGMA_S <= SIGMA_T (default 0.05,0.08)")
        ->type_name("SIGMA_S,SIGMA_T");
    app.add_option("--sm-res", raw.sm_res, "volumetric mode: the spot light's shadow map is R x R, a power of two in 2..4096 (1024)")
        ->type_name("R");
    app.add_option("--tessellation", a.tessellation,
                   "volumetric mode: the light volume's tessellation: adaptive (quadtree, flatness 1e-6) or static (2 R^2 "
                   "triangles)")
        ->type_name("KIND")
        ->check(CLI::IsMember({"adaptive", "static"}))
        ->capture_default_str();
    app.add_option("--dsm-res", raw.dsm_res, "dsm mode: the deep shadow map is R x R texels, 1..4096")
        ->type_name("R")
        ->capture_default_str();
    app.add_option("--dsm-samples", raw.dsm_samples, "dsm mode: S jittered sub-samples per texel, 1..1024")
        ->type_name("S")
        ->capture_default_str();
    app.add_option("--dsm-build", a.dsm_build,
                   "dsm mode: build the map on the GPU (the GL executor on the headless context) or with its CPU "
                   "twin (the same vertices on llvmpipe)")
        ->type_name("gpu|cpu")
        ->check(CLI::IsMember({"gpu", "cpu"}))
        ->capture_default_str();
    app.add_option("--tolerance", raw.tolerance,
                   "dsm mode: compression tolerance of the visibility functions (L-infinity), in [2^-12, 1]; 0 = 1 / (2 S)")
        ->type_name("E")
        ->capture_default_str();
    app.add_option("--aa", a.aa,
                   "hard mode: eye-view anti-aliasing (galoppo2010): off (one sample per pixel), edge (sub-samples where the "
                   "shadow-edge stencil flags a pixel), full (sub-samples in every pixel)")
        ->check(CLI::IsMember({"off", "edge", "full"}))
        ->capture_default_str();
    app.add_option("--aa-samples", raw.aa_samples, "hard mode --aa edge|full: N sub-samples per pixel, 4, 8 or 16 (rotated grid)")
        ->type_name("N")
        ->capture_default_str();
    app.add_option("--aa-stencil", a.aa_stencil,
                   "hard mode --aa edge: provable (edge == full bit for bit), chebyshev (galoppo2010's variance test: can miss "
                   "edges) or chebyshev-inner (its 'fully shadowed' claim proven by inner coverage)")
        ->check(CLI::IsMember({"provable", "chebyshev", "chebyshev-inner"}))
        ->capture_default_str();
    app.add_flag("--json", a.json, "print a one-line JSON report on stdout");
    app.add_flag("--no-ground", raw.no_ground, "no ground plane");
}

std::string lowercase(std::string s) {
    for (char& c : s) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
    return s;
}

/// A decimal number, all of `text`: [+-] digits [. digits] [e [+-] digits]; no hex, no inf or
/// nan, no spaces, no empty text. Messages name the flag and the text as given.
double parseNumber(const std::string& text, const std::string& what) {
    if (text.empty()) usageError(what, " is empty (give a number)");
    size_t i = 0;
    auto digits = [&] {
        const size_t from = i;
        while (i < text.size() && text[i] >= '0' && text[i] <= '9') ++i;
        return i - from;
    };
    if (text[i] == '+' || text[i] == '-') ++i;
    size_t mantissa = digits();
    if (i < text.size() && text[i] == '.') {
        ++i;
        mantissa += digits();
    }
    bool ok = mantissa > 0;
    if (ok && i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
        ++i;
        if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
        ok = digits() > 0;
    }
    if (!ok || i != text.size()) {
        const std::string low = lowercase(text);
        if (low.find("nan") != std::string::npos || low.find("inf") != std::string::npos)
            usageError(what, " must be finite, got '", text, "'");
        usageError(what, ": '", text, "' is not a decimal number");
    }
    errno = 0;
    const double v = std::strtod(text.c_str(), nullptr);
    if (!std::isfinite(v)) usageError(what, " is too large for a double, got '", text, "'");
    // Underflow (below ~2.2e-308, or rounded to 0 from a nonzero text): the value is not the one typed.
    if (errno == ERANGE) usageError(what, " is too small to represent (below ", std::numeric_limits<double>::min(), "), got '", text, "'");
    return v;
}

uint32_t parseCount(const std::string& text, const std::string& what, uint32_t min, uint32_t max) {
    const double v = parseNumber(text, what);
    if (v != std::floor(v) || v < min || v > max)
        usageError(what, " must be a whole number in [", min, ", ", max, "], got '", text, "'");
    return static_cast<uint32_t>(v);
}

/// "x,y,z": exactly three decimal numbers separated by single commas (spaces around them allowed);
/// messages name the flag and the value.
glm::dvec3 parseVec3(const std::string& text, const std::string& what) {
    std::vector<std::string> parts(1);
    for (char c : text) {
        if (c == ',') parts.emplace_back();
        else if (c != ' ') parts.back() += c;
    }
    if (parts.size() != 3) usageError(what, " takes x,y,z (three numbers, two commas), got '", text, "'");
    static const char* const kAxis[3] = {" x", " y", " z"};
    glm::dvec3 v;
    for (int k = 0; k < 3; ++k) {
        if (parts[k].empty()) usageError(what, kAxis[k], " is empty in '", text, "' (x,y,z takes three numbers)");
        v[k] = parseNumber(parts[k], what + kAxis[k]);
    }
    return v;
}

/// --out: a .png whose folder exists and is writable (checked here, before any work).
void checkOutPath(const std::string& out) {
    const fs::path path(out);
    const std::string extension = lowercase(path.extension().string());
    if (extension.empty()) usageError("--out '", out, "' has no extension (supported: .png)");
    if (extension != ".png") usageError("--out '", out, "': unknown extension '", path.extension().string(), "' (supported: .png)");
    const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
    std::error_code error;
    if (!fs::is_directory(folder, error)) usageError("--out '", out, "': folder '", folder.string(), "' does not exist");
    if (::access(folder.c_str(), W_OK) != 0)
        usageError("--out '", out, "': folder '", folder.string(), "' is not writable (", std::strerror(errno), ")");
    if (fs::is_directory(path, error)) usageError("--out '", out, "' is a folder");
    if (fs::exists(path, error) && ::access(path.c_str(), W_OK) != 0)
        usageError("--out '", out, "' exists and is not writable (", std::strerror(errno), ")");
    // access() says yes to root everywhere (/proc, read-only mounts): create the file to be sure,
    // and remove it again, so a failing run leaves nothing behind.
    if (!fs::exists(path, error)) {
        std::FILE* probe = std::fopen(out.c_str(), "wb");
        if (probe == nullptr) usageError("--out '", out, "' cannot be created (", std::strerror(errno), ")");
        std::fclose(probe);
        std::remove(out.c_str());
    }
}

/// --mode dsm's options (box filter over the texel's own sub-samples, one level: the lookup is
/// bilinear at level 0).
penumbra::DsmOptions dsmOptions(const Args& a) {
    penumbra::DsmOptions o;
    o.resolution = a.dsm_res;
    o.samples = a.dsm_samples;
    o.tolerance = static_cast<float>(a.tolerance);
    // A tolerance that rounds to 0 in float must not select the default: the setup rejects this.
    if (a.tolerance != 0.0 && o.tolerance == 0.0f) o.tolerance = std::numeric_limits<float>::denorm_min();
    o.levels = 1;
    return o;
}

/// A whole number in [0, 2^32) (the range is the consumer's to check).
uint32_t parseWhole(const std::string& text, const std::string& what) {
    const double v = parseNumber(text, what);
    if (v != std::floor(v) || v < 0 || v > double(std::numeric_limits<uint32_t>::max()))
        usageError(what, " must be a whole number, got '", text, "'");
    return static_cast<uint32_t>(v);
}

void checkArgs(const CLI::App& app, Args& a, const RawArgs& raw) {
    const bool hard = a.mode == "hard", soft = a.mode == "soft", hpc = a.mode == "hpc", dsm = a.mode == "dsm";
    const bool volumetric = a.mode == "volumetric";
    a.ground = !raw.no_ground;
    for (const ModeFlag& f : kModeFlags) {
        if (app.count(f.flag) > 0 &&
            !(volumetric ? f.volumetric : hard ? f.hard : soft ? f.soft : hpc ? f.hpc : dsm ? f.dsm : f.reference))
            usageError(f.flag, " is not used by --mode ", a.mode, " (",
                       volumetric && !f.volumetric && f.why_not != kVolumetricOnly ? kVolumetricWhyNot
                       : dsm && f.dsm_why_not                                       ? f.dsm_why_not
                                                                                     : f.why_not,
                       ")");
    }
    if (volumetric) {
        const size_t comma = raw.fog.find(',');
        if (comma == std::string::npos || raw.fog.find(',', comma + 1) != std::string::npos)
            usageError("--fog takes SIGMA_S,SIGMA_T (scattering, extinction per world unit), got '", raw.fog, "'");
        a.fog_sigma_s = parseNumber(raw.fog.substr(0, comma), "--fog's SIGMA_S");
        a.fog_sigma_t = parseNumber(raw.fog.substr(comma + 1), "--fog's SIGMA_T");
        if (!(std::isfinite(a.fog_sigma_s) && std::isfinite(a.fog_sigma_t) && a.fog_sigma_s > 0 && a.fog_sigma_t >= a.fog_sigma_s))
            usageError("--fog needs 0 < SIGMA_S <= SIGMA_T, both finite (extinction = scattering + absorption), got '", raw.fog, "'");
        a.sm_res = parseCount(raw.sm_res, "--sm-res", 2, 4096);
        if ((a.sm_res & (a.sm_res - 1)) != 0) usageError("--sm-res must be a power of two in [2, 4096], got '", raw.sm_res, "'");
    }
    const std::string samples = app.count("--samples") > 0 ? raw.samples : soft || hpc ? "128" : "64";
    a.samples = parseCount(samples, "--samples", 1, 1u << 16);
    if ((soft || hpc) && (a.samples < 32 || a.samples > 1024 || a.samples % 32 != 0))
        usageError("--mode ", a.mode, " draws light-sample sets (penumbra/light_samples.hpp): --samples must be a multiple "
                   "of 32 in [32, 1024], got '", samples, "'");
    a.lut_res = parseCount(raw.lut_res, "--lut-res", 16, 256);
    if (a.lut_res % 2 != 0) usageError("--lut-res must be even, got '", raw.lut_res, "'");
    a.sets = parseCount(app.count("--sets") > 0 ? raw.sets : hpc ? "8" : raw.sets, "--sets", 1, 64);  // laine2005 §3.4: 8
    a.grid = parseCount(raw.grid, "--grid", 16, 4096);
    a.rotations = parseCount(raw.rotations, "--rotations", 1, 256);
    a.width = parseCount(raw.width, "--width", 1, 16384);
    a.height = parseCount(raw.height, "--height", 1, 16384);
    if (app.count("--light-radius") > 0) {
        a.light_radius = parseNumber(raw.light_radius, "--light-radius");
        if (!(a.light_radius > 0)) usageError("--light-radius must be > 0, got '", raw.light_radius, "'");
    }
    if (app.count("--light-pos") > 0) {
        a.light_pos = parseVec3(raw.light_pos, "--light-pos");
        a.has_light_pos = true;
    }
    if (app.count("--origin") > 0) a.origin = parseVec3(raw.origin, "--origin");
    {
        const std::vector<std::string>& names = hard ? kHardSkips : kSoftSkips;
        a.skip_list.clear();
        if (a.skips == "all") {
            a.skip_list = names;
        } else if (a.skips != "none") {
            std::istringstream in(a.skips);
            std::string name;
            if (a.skips.empty() || a.skips.front() == ',' || a.skips.back() == ',')
                usageError("--skips: '", a.skips, "' has an empty name (all, none, or a comma list of names)");
            while (std::getline(in, name, ',')) {
                if (name.empty()) usageError("--skips: '", a.skips, "' has an empty name (all, none, or a comma list of names)");
                if (std::find(names.begin(), names.end(), name) == names.end()) {
                    std::string valid;
                    for (const std::string& n : names) valid += (valid.empty() ? "" : ", ") + n;
                    usageError("--skips: '", name, "' is not a skip of --mode ", a.mode, " (all, none, or a comma list of: ",
                               valid, ")");
                }
                if (!a.skip(name.c_str())) a.skip_list.push_back(name);
            }
            if (a.skip_list.empty()) usageError("--skips: '", a.skips, "' names no skip (all, none, or a comma list)");
        }
    }
    a.frames = parseCount(raw.frames, "--frames", 1, 1024);
    a.frames_reference = parseCount(raw.frames_reference, "--frames-reference", 1, 1u << 16);
    if (a.frames > 1 && (a.samples < 32 || a.samples > 1024 || a.samples % 32 != 0))
        usageError("--frames draws light-sample sets (penumbra/light_samples.hpp): --samples must be a multiple of 32 in "
                   "[32, 1024], got '", raw.samples, "'");
    {
        a.opacity = parseNumber(raw.opacity, "--opacity");
        if (!(a.opacity >= 0.0 && a.opacity <= 1.0))
            usageError("--opacity must be in [0, 1] (the fraction of light a caster stops), got '", raw.opacity, "'");
    }
    if (a.aa != "off" && a.check_skips)
        usageError("--check-skips is not used with --aa ", a.aa, " (the anti-aliased frames run with the skips as given)");
    a.aa_samples = parseWhole(raw.aa_samples, "--aa-samples");
    if (a.aa_samples != 4 && a.aa_samples != 8 && a.aa_samples != 16)
        usageError("--aa-samples must be 4, 8 or 16, got '", raw.aa_samples, "'");
    if (a.aa == "off" && (app.count("--aa-samples") > 0 || app.count("--aa-stencil") > 0))
        usageError(app.count("--aa-samples") > 0 ? "--aa-samples" : "--aa-stencil", " needs --aa edge or --aa full");
    a.dsm_res = parseWhole(raw.dsm_res, "--dsm-res");
    a.dsm_samples = parseWhole(raw.dsm_samples, "--dsm-samples");
    a.tolerance = parseNumber(raw.tolerance, "--tolerance");
    if (dsm) {
        // The block's own setup is the authority on the ranges (and their combinations): its
        // message names the bad value; the flags as given are put in front of it.
        try {
            (void)penumbra::deepShadowMapSetup(dsmOptions(a));
        } catch (const penumbra::Error& e) {
            usageError("--dsm-res ", raw.dsm_res, " --dsm-samples ", raw.dsm_samples, " --tolerance ", raw.tolerance,
                       " rejected: ", e.what());
        }
    }
    checkOutPath(a.out);
}

// =============================================================================================
// Checks that need the scene: the light, and memory

/// Box of every mesh vertex (double).
std::pair<glm::dvec3, glm::dvec3> sceneBounds(const penumbra::scene::Scene& scene) {
    glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
    for (const auto& mesh : scene.meshes) {
        for (const glm::vec3& p : mesh.positions) {
            lo = glm::min(lo, glm::dvec3(p));
            hi = glm::max(hi, glm::dvec3(p));
        }
    }
    return {lo, hi};
}

std::string vec3Text(const glm::dvec3& v) {
    std::ostringstream out;
    out.precision(9);
    out << "(" << v.x << ", " << v.y << ", " << v.z << ")";
    return out.str();
}

/// The spherical light must stay clear of the scene: a radius no larger than the distance from
/// its centre to the scene's bounds (larger spheres put light samples inside the geometry, and a
/// huge one, e.g. 1e30, makes the oracle's work unbounded).
void checkLight(const penumbra::scene::Scene& scene, const glm::dvec3& centre, double radius) {
    const auto [lo, hi] = sceneBounds(scene);
    if (!(lo.x <= hi.x)) return;  // no vertices: nothing to reach
    const double distance = glm::length(centre - glm::clamp(centre, lo, hi));
    if (distance == 0.0) {
        std::ostringstream out;
        out.precision(9);
        out << "the light's centre " << vec3Text(centre) << " lies inside the scene's bounds " << vec3Text(lo) << " .. "
            << vec3Text(hi) << ": a spherical light must lie outside them; move it with --light-pos";
        usageError(out.str());
    }
    if (radius >= distance) {
        std::ostringstream out;
        out.precision(9);
        out << "the light (centre " << vec3Text(centre) << ", radius " << radius << ") reaches into the scene: its centre is "
            << distance << " from the scene's bounds " << vec3Text(lo) << " .. " << vec3Text(hi)
            << "; use --light-radius below " << distance << " or move it with --light-pos";
        usageError(out.str());
    }
}

uint64_t physicalMemoryBytes() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
    return pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) : 0;
}

std::string gib(double bytes) {
    char text[32];
    std::snprintf(text, sizeof text, "%.2f GiB", bytes / double(1ull << 30));
    return text;
}

/// What the run will allocate, by part (rough upper bounds: every pixel a view sample).
struct MemoryEstimate {
    std::vector<std::pair<std::string, double>> parts;
    double total() const {
        double sum = 0;
        for (const auto& p : parts) sum += p.second;
        return sum;
    }
};

MemoryEstimate estimateMemory(const Args& args, size_t triangles) {
    const double pixels = double(args.width) * double(args.height);
    MemoryEstimate m;
    // Oracle: mesh in double, triangle records, BVH nodes, merged copies (~ 400 B per triangle).
    m.parts.emplace_back("scene and oracle", 400.0 * double(triangles));
    if (args.mode == "hard") {
        // llvmpipe buffers live in host memory: G-buffer textures + SSBO copies (~ 100 B/pixel),
        // lists sized for every pixel a sample (counts/offsets per light texel, position, id,
        // slot, texel, state, shadow bit per sample: ~ 40 B), host read-backs (~ 52 B), counted
        // twice for driver-side copies.
        m.parts.emplace_back("G-buffer and view samples", 2.0 * 100.0 * pixels + 52.0 * pixels);
        m.parts.emplace_back("sample lists", 2.0 * 40.0 * pixels);
        if (args.reference) m.parts.emplace_back("oracle check", (24.0 + 4.0 + 8.0) * pixels);
        if (args.aa != "off") {
            // --aa: sub-samples, stencil records (~ 64 B per pixel) and per point of the sample
            // buffer (1 + N per pixel) two vec4, the lists' ~ 40 B, its state, counted twice;
            // --reference: the full buffer read back and the oracle's verdict per point, and 64
            // dense points per pixel (vec4 and verdict, twice for the footprint copy).
            const double points = (1.0 + args.aa_samples) * pixels;
            m.parts.emplace_back("anti-aliasing sample buffer", 2.0 * (64.0 * pixels + (32.0 + 40.0 + 4.0) * points));
            if (args.reference) m.parts.emplace_back("anti-aliasing oracle", (17.0 + 4.0) * points + 2.0 * 17.0 * 64.0 * pixels);
        }
    } else if (args.mode == "soft") {
        // As hard, plus the masks (N bits per sample, GPU + read-back) and the LUT (K sets x
        // ceil(N / 128) tables x R^3 uvec4 texels, twice for the certified masks), counted twice
        // (llvmpipe keeps buffers in host memory; the generator's scratch).
        const double words = std::ceil(double(args.samples) / 32.0);
        m.parts.emplace_back("G-buffer and view samples", 2.0 * 100.0 * pixels + 52.0 * pixels);
        m.parts.emplace_back("sample lists and masks", 2.0 * (40.0 + 8.0 * words) * pixels);
        if (args.lut != "brute") {
            const double r = args.lut_res;
            m.parts.emplace_back("light-sample LUT", 2.0 * double(args.sets) * std::ceil(args.samples / 128.0) * r * r * r *
                                                         16.0 * (args.lut == "exact" ? 2.0 : 1.0));
        }
        if (args.reference) m.parts.emplace_back("oracle masks (blocked + ties)", (24.0 + 2.0 * 4.0 * words) * pixels);
    } else if (args.mode == "hpc") {
        // Penumbra casting: receivers in double and their BVH (~ 64 B), the masks (blocked and
        // ties; on demand, counted in full here), the oracle's masks with --reference.
        const double words = std::ceil(double(args.samples) / 32.0);
        m.parts.emplace_back("view samples and receiver hierarchy", (8.0 + 24.0 + 4.0 + 24.0 + 24.0 + 64.0) * pixels);
        m.parts.emplace_back("penumbra casting masks", 2.0 * 4.0 * words * pixels);
        if (args.reference) m.parts.emplace_back("oracle masks (blocked + ties)", 2.0 * 4.0 * words * pixels);
    } else if (args.mode == "dsm") {
        // The CPU build: R^2 S + 1 list offsets, and per fragment a sort record (24 B) plus the
        // fragment (20 B) and about one map vertex (8 B). The fragment count is the casters' depth
        // complexity per sub-sample, unknown before rasterizing: 4 is assumed (the hairball has ~7
        // inside its disc, which covers part of the map). Receivers: primary hits, oracle segments
        // and results with --reference.
        const double sub_samples = double(args.dsm_res) * double(args.dsm_res) * double(args.dsm_samples);
        m.parts.emplace_back("view samples", (8.0 + 24.0 + 24.0 + 4.0 + 24.0 + 4.0 + 8.0) * pixels);
        m.parts.emplace_back("deep shadow map build (depth complexity 4 assumed)", (4.0 + 4.0 * (24.0 + 20.0 + 8.0)) * sub_samples);
        if (args.reference) m.parts.emplace_back("oracle transmittance", (48.0 + 56.0) * pixels);
    } else {
        const double words = std::ceil(double(args.samples) / 32.0);
        m.parts.emplace_back("view samples", (8.0 + 24.0 + 4.0 + 24.0 + 24.0) * pixels);
        m.parts.emplace_back("oracle masks (blocked + ties)", 2.0 * 4.0 * words * pixels);
        m.parts.emplace_back("light samples", 24.0 * double(args.samples));
    }
    if (args.frames > 1 && args.mode != "hard" && args.mode != "dsm") {
        // --frames: the oracle image (blocked + ties masks of --frames-reference samples, the
        // receivers in double) and the running sums.
        const double reference_words = std::ceil(double(args.frames_reference) / 32.0);
        m.parts.emplace_back("temporal reference image", (2.0 * 4.0 * reference_words + 24.0 + 8.0 + 12.0) * pixels);
    }
    m.parts.emplace_back("image and PNG", 6.0 * pixels);
    return m;
}

/// Refuses a run whose estimate exceeds 80% of the machine's physical memory, with the numbers.
void checkMemory(const Args& args, size_t triangles) {
    const MemoryEstimate m = estimateMemory(args, triangles);
    const uint64_t physical = physicalMemoryBytes();
    if (physical == 0 || m.total() <= 0.8 * double(physical)) return;
    std::ostringstream out;
    out << args.width << "x" << args.height;
    if (args.mode == "dsm") out << " with a " << args.dsm_res << "^2 x " << args.dsm_samples << " deep shadow map";
    else if (args.mode != "hard") out << " with " << args.samples << " light samples";
    out << " needs about " << gib(m.total()) << " (";
    for (size_t i = 0; i < m.parts.size(); ++i) out << (i ? ", " : "") << m.parts[i].first << " " << gib(m.parts[i].second);
    out << ") but this machine has " << gib(double(physical))
        << " of memory (sysconf: physical pages; the limit is 80%); use a smaller --width/--height";
    if (args.mode == "dsm") out << " or a smaller --dsm-res / --dsm-samples";
    else if (args.mode != "hard") out << " or fewer --samples";
    if (args.mode == "soft") out << " (or a smaller --lut-res / --sets)";
    usageError(out.str());
}

// =============================================================================================
// Running

/// The light's first frustum over the view samples' box; a light no frustum can frame from there
/// (inside the box, or seeing it wider than 85 degrees) is the user's to move: exit 2, naming the flag.
glm::mat4 lightFrustumOrRefuse(const glm::vec4& light, const glm::vec3& lo, const glm::vec3& hi) {
    try {
        return penumbra::lightViewProjectionForBounds(light, lo, hi);
    } catch (const penumbra::Error& e) {
        usageError("--light-pos ", vec3Text(glm::dvec3(glm::vec3(light))), " cannot light the view samples from there: ", e.what());
    }
}

/// Fault injection for the tests of the checks themselves (ctest's soft_shadows.hostile.*):
/// PENUMBRA_DEMO_FAULT=skips flips one bit of the skips-on masks before --check-skips compares
/// them, =reference flips bit 0 of every mask before --reference compares them with the oracle.
bool faultInjected(const char* what) {
    const char* fault = std::getenv("PENUMBRA_DEMO_FAULT");
    return fault != nullptr && std::strcmp(fault, what) == 0;
}

/// A run whose own checks failed exits 1 after its report: --check-skips found words that differ
/// (the skips promise never to change a bit), or an exact mode's --reference found non-tie bits
/// that differ from the oracle. Returns the exit code.
int checksVerdict(const char* mode, uint64_t skips_mismatched_words, uint64_t reference_mismatched, const char* what) {
    int code = 0;
    if (skips_mismatched_words > 0) {
        std::fprintf(stderr, "soft_shadows: --check-skips failed: %llu shadow words of --mode %s differ with every skip off (the skips must not change a bit)\n",
                     static_cast<unsigned long long>(skips_mismatched_words), mode);
        code = 1;
    }
    if (reference_mismatched > 0) {
        std::fprintf(stderr, "soft_shadows: --reference failed: %llu %s of --mode %s differ from the oracle (an exact mode must match it)\n",
                     static_cast<unsigned long long>(reference_mismatched), what, mode);
        code = 1;
    }
    return code;
}

double msSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/// Percent done on stderr, at most every few seconds (so short runs print nothing).
class Progress {
public:
    Progress(const char* what, size_t total) : what_(what), total_(total) {}
    void update(size_t done) {
        const auto now = std::chrono::steady_clock::now();
        if (now - last_ < std::chrono::seconds(kIntervalSeconds) || total_ == 0) return;
        last_ = now;
        printed_ = true;
        std::fprintf(stderr, "soft_shadows: %s %5.1f%% (%zu of %zu, %.0f s)\n", what_, 100.0 * double(done) / double(total_),
                     done, total_, msSince(start_) / 1000.0);
    }
    ~Progress() {
        if (printed_) std::fprintf(stderr, "soft_shadows: %s done (%.0f s)\n", what_, msSince(start_) / 1000.0);
    }

private:
    static constexpr int kIntervalSeconds = 3;
    const char* what_;
    size_t total_;
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_ = start_;
    bool printed_ = false;
};

/// Runs body(i) for i in [0, n) on all cores.
template <typename Body>
void parallelFor(size_t begin, size_t end, Body body) {
    const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t) {
        pool.emplace_back([&, t] {
            for (size_t i = begin + t; i < end; i += threads) body(i);
        });
    }
    for (auto& th : pool) th.join();
}

/// Chunks of about 1/200 of the work (at least `min_chunk` items), reporting progress after each.
template <typename Body>
void inChunks(size_t n, size_t min_chunk, Progress& progress, Body body) {
    const size_t chunk = std::max(min_chunk, (n + 199) / 200);
    for (size_t begin = 0; begin < n; begin += chunk) {
        const size_t end = std::min(n, begin + chunk);
        body(begin, end);
        progress.update(end);
    }
}

/// oracle.evaluate in chunks of receivers (the oracle has no progress hook): same bits, since
/// every pair is computed independently.
penumbra::reference::VisibilityResult evaluateWithProgress(const penumbra::reference::VisibilityOracle& oracle,
                                                           const std::vector<glm::dvec3>& receivers,
                                                           const std::vector<glm::dvec3>& samples,
                                                           const penumbra::reference::VisibilityOptions& options,
                                                           const char* what) {
    penumbra::reference::VisibilityResult all;
    all.receivers = receivers.size();
    all.samples = samples.size();
    all.words_per_receiver = static_cast<uint32_t>((samples.size() + 31) / 32);
    all.blocked.assign(receivers.size() * all.words_per_receiver, 0u);
    all.ties.assign(all.blocked.size(), 0u);
    Progress progress(what, receivers.size());
    std::vector<glm::dvec3> part;
    inChunks(receivers.size(), 1024, progress, [&](size_t begin, size_t end) {
        part.assign(receivers.begin() + static_cast<std::ptrdiff_t>(begin), receivers.begin() + static_cast<std::ptrdiff_t>(end));
        const penumbra::reference::VisibilityResult r = oracle.evaluate(part, samples, options);
        std::copy(r.blocked.begin(), r.blocked.end(), all.blocked.begin() + static_cast<std::ptrdiff_t>(begin * all.words_per_receiver));
        std::copy(r.ties.begin(), r.ties.end(), all.ties.begin() + static_cast<std::ptrdiff_t>(begin * all.words_per_receiver));
        all.tie_count += r.tie_count;
        all.nodes_visited += r.nodes_visited;
        all.triangle_tests += r.triangle_tests;
    });
    return all;
}

Json reportHead(const Args& args, const char* mode) {
    Json j;
    j["penumbra_version"] = std::to_string(penumbra::kVersionMajor) + "." + std::to_string(penumbra::kVersionMinor) + "." +
                            std::to_string(penumbra::kVersionPatch);
    j["scene"] = args.scene;
    j["mode"] = mode;
    j["origin"] = Json::array({args.origin.x, args.origin.y, args.origin.z});
    j["shading"] = args.shading;
    return j;
}

/// One line on stdout; a path that is not UTF-8 gets U+FFFD instead of failing the report.
void printReport(const Json& j) {
    std::printf("%s\n", j.dump(-1, ' ', false, Json::error_handler_t::replace).c_str());
}

Json vec3Json(const glm::dvec3& v) { return Json::array({v.x, v.y, v.z}); }

/// The scene merged into one triangle list, with a per-triangle material (0 = ground).
struct MergedScene {
    std::vector<glm::dvec3> positions, normals;
    std::vector<uint32_t> indices;
    std::vector<uint8_t> material;
};

MergedScene merge(const penumbra::scene::Scene& scene) {
    MergedScene m;
    for (const auto& mesh : scene.meshes) {
        const uint32_t base = static_cast<uint32_t>(m.positions.size());
        for (size_t v = 0; v < mesh.positions.size(); ++v) {
            m.positions.emplace_back(mesh.positions[v]);
            m.normals.emplace_back(v < mesh.normals.size() ? glm::dvec3(mesh.normals[v]) : glm::dvec3(0, 1, 0));
        }
        for (uint32_t idx : mesh.indices) m.indices.push_back(base + idx);
        m.material.insert(m.material.end(), mesh.indices.size() / 3, mesh.name == "ground" ? 0 : 1);
    }
    return m;
}

/// Direct-light shading of a surface point: Lambert with the smooth normal (phong), or bent-normal
/// shading (sintorn2008 §4.3, penumbra/bent_normals.hpp): l_bend per vertex toward the light centre,
/// interpolated with the point's barycentrics in its triangle.
class DirectShading {
public:
    DirectShading(const MergedScene& merged, const glm::dvec3& light) : merged_(merged) {
        std::vector<glm::vec3> positions(merged.positions.begin(), merged.positions.end());
        // Creases (default 60 degrees) split a vertex into one bent vertex per smooth group: a
        // cube's lit face is not darkened by the faces that turn away from the light at its corners.
        mesh_ = penumbra::bentNormalMesh(positions.data(), positions.size(), merged.indices.data(), merged.indices.size());
        l_bend_.resize(mesh_.bentVertexCount());
        for (uint32_t v = 0; v < l_bend_.size(); ++v)
            l_bend_[v] = penumbra::bentLight(mesh_, v, positions[mesh_.source[v]], glm::vec3(light));
    }
    /// n: the smooth shading normal, l: unit direction to the light, p: the point on `triangle`.
    double direct(bool bent, uint32_t triangle, const glm::dvec3& p, const glm::dvec3& n, const glm::dvec3& l) const {
        const double l_f = glm::dot(n, l);
        if (!bent) return std::max(0.0, l_f);
        const uint32_t* t = &merged_.indices[size_t(triangle) * 3];
        const glm::dvec3 a = merged_.positions[t[0]], b = merged_.positions[t[1]], c = merged_.positions[t[2]];
        // Barycentrics of p's projection onto the triangle's plane (clamped: p lies on it up to rounding).
        const glm::dvec3 e1 = b - a, e2 = c - a, d = p - a;
        const double d11 = glm::dot(e1, e1), d12 = glm::dot(e1, e2), d22 = glm::dot(e2, e2);
        const double det = d11 * d22 - d12 * d12;
        double u = 0, v = 0;
        if (det > 0) {
            u = std::clamp((d22 * glm::dot(d, e1) - d12 * glm::dot(d, e2)) / det, 0.0, 1.0);
            v = std::clamp((d11 * glm::dot(d, e2) - d12 * glm::dot(d, e1)) / det, 0.0, 1.0 - u);
        }
        const uint32_t* corners = &mesh_.indices[size_t(triangle) * 3];  // the corners' bent vertices
        const float lb = float((1.0 - u - v) * l_bend_[corners[0]] + u * l_bend_[corners[1]] + v * l_bend_[corners[2]]);
        return penumbra::bentDirect(lb, float(l_f));
    }

private:
    const MergedScene& merged_;
    penumbra::BentNormalMesh mesh_;
    std::vector<float> l_bend_;
};

/// <out stem><suffix>.png beside `out`.
std::string siblingPath(const std::string& out, const char* suffix) {
    const fs::path path(out);
    return (path.parent_path() / (path.stem().string() + suffix + ".png")).string();
}

/// <out stem>_shading.png beside `out`.
std::string shadingComparePath(const std::string& out) { return siblingPath(out, "_shading"); }

/// Side by side, left to right (same sizes).
penumbra::scene::ImageRgb8 sideBySide(const std::vector<const penumbra::scene::ImageRgb8*>& parts) {
    penumbra::scene::ImageRgb8 out;
    out.width = parts[0]->width * static_cast<uint32_t>(parts.size());
    out.height = parts[0]->height;
    out.pixels.resize(size_t(out.width) * out.height * 3);
    for (size_t k = 0; k < parts.size(); ++k) {
        const penumbra::scene::ImageRgb8& part = *parts[k];
        for (uint32_t y = 0; y < part.height; ++y)
            std::memcpy(&out.pixels[(size_t(y) * out.width + k * part.width) * 3], &part.pixels[size_t(y) * part.width * 3],
                        size_t(part.width) * 3);
    }
    return out;
}

/// Writes the Phong | bent image pair side by side.
void writeShadingCompare(const std::string& out, const penumbra::scene::ImageRgb8& phong, const penumbra::scene::ImageRgb8& bent) {
    penumbra::scene::writePng(shadingComparePath(out), sideBySide({&phong, &bent}));
}

/// Coplanar tolerance of the exact test for depth-reconstructed view samples: above the ~1e-5
/// relative error of positions rebuilt from a 32-bit float depth buffer, so a sample is not
/// shadowed by the very surface it was reconstructed from (docs/design.md).
constexpr double kDepthCoplanarEpsilon = 2e-5;
/// lightLutSetup's largest certified tolerance (penumbra/light_lut.hpp: tolerance in [0, 1e-2]).
constexpr double kMaxLutTolerance = 1e-2;

/// The view samples the GPU pipelines get, from one G-buffer pass of the camera: the engine's
/// depth buffer (positions reconstructed on the GPU) or the G-buffer's exact surface points.
/// Per pixel, GL's bottom row first (sample id = y * width + x in both inputs).
struct GpuViewSamples {
    penumbra::scene::GBuffer gbuffer;
    penumbra::SampleListsView view;
    bool depth_input = false;
    std::vector<glm::vec4> exact_positions;  // the G-buffer's surface points (w = 0: background)
    std::vector<glm::vec4> faces;            // face normal, w = triangle id (float bits)
    std::vector<float> shading;              // shading normal, RGBA per pixel
    std::vector<glm::vec4> positions;        // the very floats the pipeline tests
    glm::vec3 lo{0.0f}, hi{0.0f};            // box of the surface points
    size_t count = 0;                        // surface pixels
    double ms = 0;

    GpuViewSamples(const Args& args, const penumbra::scene::Scene& scene, const penumbra::scene::GpuScene& gpu)
        : gbuffer(args.width, args.height), depth_input(args.view_samples == "depth") {
        const auto t0 = std::chrono::steady_clock::now();
        const uint32_t w = args.width, h = args.height;
        const glm::mat4 camera = scene.camera.projection(float(w) / float(h)) * scene.camera.view();
        gbuffer.render(gpu, camera);
        exact_positions = gbuffer.positionBuffer().download<glm::vec4>();
        faces = gbuffer.faceBuffer().download<glm::vec4>();
        shading.resize(size_t(w) * h * 4);
        glGetTextureImage(gbuffer.shadingNormalTexture(), 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(shading.size() * 4),
                          shading.data());
        view.width = w;
        view.height = h;
        view.inverse_view_projection = glm::inverse(camera);
        positions = exact_positions;
        if (depth_input) {
            std::vector<float> depth(size_t(w) * h);
            glGetTextureImage(gbuffer.depthTexture(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(depth.size() * 4), depth.data());
            positions = penumbra::reconstructViewSamples(view, depth.data());
        }
        std::tie(lo, hi) = penumbra::viewSampleBounds(exact_positions.data(), exact_positions.size(), &count);
        glFinish();
        ms = msSince(t0);
    }
    /// Depth input: replaces `positions` with the positions the GPU reconstructed and tested, read
    /// back from a pipeline's lists (what the oracle must be asked about: a driver whose division
    /// and FMA round unlike the CPU twin reconstructs other last bits than reconstructViewSamples;
    /// on llvmpipe they are the same). Samples the lists do not hold keep the twin's position.
    /// Returns how many listed samples differ from the twin. Reads back and waits: after the frame.
    size_t adoptGpuPositions(const penumbra::SampleListsSetup& setup, const penumbra::SampleListsBuffers& buffers) {
        if (!depth_input) return 0;
        const std::vector<glm::vec4> tested = penumbra::listedPositions(penumbra::downloadSampleLists(setup, buffers), positions);
        size_t differ = 0;
        for (size_t id = 0; id < positions.size(); ++id) differ += std::memcmp(&tested[id], &positions[id], sizeof(glm::vec4)) != 0;
        positions = tested;
        return differ;
    }
    bool surface(size_t pixel) const { return exact_positions[pixel].w != 0.0f; }
    uint32_t triangle(size_t pixel) const {
        uint32_t t = 0;
        std::memcpy(&t, &faces[pixel].w, 4);
        return t;
    }
};

/// Shades the G-buffer's pixels with direct light times `visible` (per pixel; ignored where no
/// surface): [0] Phong, [1] bent. Rows flipped (GL's bottom row first, PNG's top row first).
void shadeGpuImages(const GpuViewSamples& v, const MergedScene& merged, const glm::dvec3& light_pos,
                    const std::vector<float>& visible, penumbra::scene::ImageRgb8 images[2]) {
    const DirectShading direct(merged, light_pos);
    const std::vector<uint8_t>& material = merged.material;
    const uint32_t w = v.view.width, h = v.view.height;
    for (int b = 0; b < 2; ++b) {
        images[b].width = w;
        images[b].height = h;
        images[b].pixels.assign(size_t(w) * h * 3, 0);
    }
    const glm::vec3 albedo[2] = {{0.75f, 0.75f, 0.72f}, {0.85f, 0.45f, 0.2f}};
    for (uint32_t y = 0; y < h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            glm::vec3 c[2] = {glm::vec3(0.08f, 0.09f, 0.12f), glm::vec3(0.08f, 0.09f, 0.12f)};
            if (v.surface(i)) {
                const uint32_t triangle = v.triangle(i);
                const glm::vec3 n = glm::normalize(glm::vec3(v.shading[i * 4], v.shading[i * 4 + 1], v.shading[i * 4 + 2]));
                const glm::vec3 l = glm::normalize(glm::vec3(light_pos) - glm::vec3(v.exact_positions[i]));
                const float lit = std::clamp(visible[i], 0.0f, 1.0f);
                const bool known = triangle < material.size();
                for (int bent = 0; bent < 2; ++bent) {
                    const float light = known ? float(direct.direct(bent == 1, triangle, glm::dvec3(v.exact_positions[i]),
                                                                    glm::dvec3(n), glm::dvec3(l)))
                                              : std::max(0.0f, glm::dot(n, l));
                    c[bent] = albedo[known ? material[triangle] : 1] * (0.12f + 0.88f * light * lit);
                }
            }
            const size_t o = (size_t(h - 1 - y) * w + x) * 3;
            for (int b = 0; b < 2; ++b)
                for (int k = 0; k < 3; ++k) images[b].pixels[o + k] = penumbra::scene::linearToSrgb8(c[b][k]);
        }
    }
}

/// A pipeline's frame: one warm-up run, then one timed (glFinish, wall clock). Milliseconds, or -1
/// after printing the Status a run returned.
template <typename Run>
double timedFrame(const Run& run, const char* pipeline) {
    penumbra::Status status = run();  // warm-up
    double ms = 0;
    if (status == penumbra::Status::Ok) {
        glFinish();  // the warm-up's work is not the timed frame's
        const auto t0 = std::chrono::steady_clock::now();
        status = run();
        glFinish();
        ms = msSince(t0);
    }
    if (status == penumbra::Status::Ok) return ms;
    std::fprintf(stderr, "soft_shadows: the %s pipeline returned '%s'\n", pipeline, penumbra::statusName(status));
    return -1;
}

// --mode hard --aa edge|full: eye-view anti-aliasing of the hard shadows (galoppo2010,
// penumbra/gl/shadow_edge_stencil.hpp) on the G-buffer's view samples and face normals. Off, edge
// and full all run (one warm-up, one timed frame each), so the report compares them; the image is
// --aa's. Per frame: the stencil (--aa-stencil), the extended sample buffer (centres, plus N
// sub-samples of the flagged pixels for edge or of every pixel for full), the hard pipeline on it
// and the resolve to a lit fraction per pixel.

/// The oracle's verdicts on `ids` (hardReference: the very floats the GPU tested), in chunks with
/// progress on stderr. Only ids, blocked and tie are filled.
penumbra::reference::HardReference hardReferenceWithProgress(const penumbra::reference::VisibilityOracle& oracle,
                                                             const std::vector<glm::vec4>& positions,
                                                             const std::vector<uint32_t>& ids,
                                                             const penumbra::reference::HardLight& light,
                                                             const penumbra::reference::VisibilityOptions& options,
                                                             const char* what) {
    penumbra::reference::HardReference all;
    all.ids = ids;
    all.blocked.reserve(ids.size());
    all.tie.reserve(ids.size());
    Progress progress(what, ids.size());
    std::vector<uint32_t> part;
    inChunks(ids.size(), 4096, progress, [&](size_t begin, size_t end) {
        part.assign(ids.begin() + static_cast<std::ptrdiff_t>(begin), ids.begin() + static_cast<std::ptrdiff_t>(end));
        const penumbra::reference::HardReference r = penumbra::reference::hardReference(oracle, positions, part, light, options);
        all.blocked.insert(all.blocked.end(), r.blocked.begin(), r.blocked.end());
        all.tie.insert(all.tie.end(), r.tie.begin(), r.tie.end());
    });
    return all;
}

/// Per point of `positions` (w == 0: none): lit (1), shadowed (0) or none / tie (2), from the
/// oracle. A point whose pixel plane faces away from the light is shadowed (aaBackFacing, the
/// pipeline's own rule: the oracle sees segments, not normals); pixel(i) names point i's pixel
/// (its normal is normals[pixel(i)]).
template <typename PixelOf>
std::vector<uint8_t> oracleLit(const penumbra::reference::VisibilityOracle& oracle, const std::vector<glm::vec4>& positions,
                               const std::vector<glm::vec4>& normals, PixelOf pixel, const glm::vec4& light,
                               const penumbra::reference::VisibilityOptions& options, const char* what) {
    std::vector<uint8_t> lit(positions.size(), 2);
    std::vector<uint32_t> ids;
    for (size_t i = 0; i < positions.size(); ++i) {
        if (positions[i].w == 0.0f) continue;
        if (penumbra::detail::aaBackFacing(light, positions[i], glm::vec3(normals[pixel(i)]))) lit[i] = 0;
        else ids.push_back(static_cast<uint32_t>(i));
    }
    const penumbra::reference::HardReference r =
        hardReferenceWithProgress(oracle, positions, ids, penumbra::reference::hardLight(light), options, what);
    for (size_t k = 0; k < ids.size(); ++k) lit[ids[k]] = r.tie[k] ? 2 : r.blocked[k] ? 0 : 1;
    return lit;
}

/// The stencil over the shaded image: grey image, flagged pixels red, `missed` pixels (edge
/// pixels the stencil left single-sampled) green. Rows flipped as the shaded images.
void writeStencilPng(const std::string& path, const penumbra::scene::ImageRgb8& shaded, const GpuViewSamples& v,
                     const std::vector<uint32_t>& words, const std::vector<uint8_t>& missed) {
    penumbra::scene::ImageRgb8 image = shaded;
    const uint32_t w = v.view.width, h = v.view.height;
    for (uint32_t y = 0; y < h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            uint8_t* c = &image.pixels[(size_t(h - 1 - y) * w + x) * 3];
            const uint8_t grey = static_cast<uint8_t>((int(c[0]) + int(c[1]) + int(c[2])) / 6);
            c[0] = c[1] = c[2] = grey;
            if (!v.surface(i)) continue;
            if (!missed.empty() && missed[i]) {
                c[0] = 40, c[1] = 255, c[2] = 60;
            } else if (words[i] & PENUMBRA_AA_FLAG) {
                c[0] = 255, c[1] = static_cast<uint8_t>(grey / 2 + 30), c[2] = static_cast<uint8_t>(grey / 2);
            }
        }
    }
    penumbra::scene::writePng(path, image);
}

/// The shadow-edge stencils --aa-stencil names (JSON keys; the flag spells chebyshev_inner
/// chebyshev-inner): provable; galoppo2010's Chebyshev test as published; the same with its
/// "fully shadowed" claim proven by inner coverage (ChebyshevStencilOptions::inner_shadow_proof).
constexpr int kAaStencils = 3;
const char* const kAaStencilNames[kAaStencils] = {"provable", "chebyshev", "chebyshev_inner"};

/// One stencil's frame: its words, the --aa edge visibility it gives, its cost and (--reference) misses.
struct AaStencilRun {
    std::vector<uint32_t> words;
    std::vector<float> visible_edge;
    std::vector<uint8_t> missed;  // per pixel: an edge pixel the stencil left single-sampled
    double stencil_ms = 0, rmse_edge = 0;
    size_t flagged = 0, missed_count = 0;
};

int runHardAa(const Args& args, const penumbra::reference::VisibilityOracle& oracle, const MergedScene& merged,
              const glm::dvec3& light_pos, const penumbra::scene::GpuScene& gpu, const GpuViewSamples& v,
              const std::string& renderer, double load_ms, std::chrono::steady_clock::time_point t_start) {
    using penumbra::AaMode;
    using penumbra::Status;
    using penumbra::gl::Buffer;
    using penumbra::gl::ShadowEdgeStencil;
    const uint32_t w = args.width, h = args.height, p = w * h, n = args.aa_samples;
    const uint32_t all = p * (1 + n);  // checkMemory bounds the image: p (1 + 16) < 2^31
    penumbra::AliasFreeHardOptions options;
    options.grid_width = w;
    options.grid_height = h;
    options.count_work = true;
    if (v.depth_input) options.coplanar_epsilon = kDepthCoplanarEpsilon;
    options.scene_extent = oracle.sceneExtent();  // the oracle's E: far lights keep their shadows
    // --skips: the hard pipeline's skips but cull (light_facing_only): the stencil classifies every caster.
    options.fit_frustum = args.skip("fit");
    options.skip_shadowed = args.skip("shadowed");
    options.clip_to_box = args.skip("box");
    options.skip_empty_texels = args.skip("empty");
    penumbra::AaPatternOptions pattern;
    pattern.samples = n;
    auto range = [](const Buffer& b) { return penumbra::BufferRange{b.id(), 0, b.size()}; };
    const Buffer centres = Buffer::fromVector(v.positions);
    const penumbra::BufferRange normals{v.gbuffer.faceBuffer().id(), 0, v.gbuffer.faceBuffer().size()};
    penumbra::gl::AaCasterBuffers casters;
    casters.positions = {gpu.vertexBuffer(), 0, 24ull * gpu.positions().size()};
    casters.indices = {gpu.indexBuffer(), 0, 4ull * gpu.indexCount()};
    casters.index_count = gpu.indexCount();
    casters.stride = 24;

    // The one --aa-stencil names; with --reference every kind (each one's misses and cost).
    const int main_kind = args.aa_stencil == "provable" ? 0 : args.aa_stencil == "chebyshev" ? 1 : 2;
    std::unique_ptr<ShadowEdgeStencil> stencils[kAaStencils];
    for (int k = 0; k < kAaStencils; ++k) {
        if (!args.reference && k != main_kind) continue;
        penumbra::ChebyshevStencilOptions chebyshev;
        chebyshev.inner_shadow_proof = k == 2;
        stencils[k] = std::make_unique<ShadowEdgeStencil>(
            w, h, options, pattern, penumbra::ProvableStencilOptions{}, 1u << 22, penumbra::ShaderLibrary::embedded(),
            k == 0 ? penumbra::gl::AaStencilKind::Provable : penumbra::gl::AaStencilKind::Chebyshev, chebyshev);
    }
    ShadowEdgeStencil& stencil = *stencils[main_kind];

    // The light's frustum must see every sub-sample too: one run for them, then the box of all points.
    penumbra::SampleListsLight light;
    light.light = glm::vec4(glm::vec3(light_pos), 1.0f);
    light.view_projection = lightFrustumOrRefuse(light.light, v.lo, v.hi);
    if (stencil.run(range(centres), normals, v.view, light, casters) != Status::Ok) {
        std::fprintf(stderr, "soft_shadows: the shadow-edge stencil rejected its inputs\n");
        return 1;
    }
    {
        glm::vec3 lo = v.lo, hi = v.hi;
        for (const glm::vec4& s : stencil.readSubSamples()) {
            if (s.w == 0.0f) continue;
            lo = glm::min(lo, glm::vec3(s));
            hi = glm::max(hi, glm::vec3(s));
        }
        light.view_projection = lightFrustumOrRefuse(light.light, lo, hi);
    }

    penumbra::AliasFreeHardShadows hard(options);
    hard.reserve(p);
    auto draw = [&](penumbra::CasterClass cls) { gpu.drawClass(cls == penumbra::CasterClass::Closed); };
    Buffer sample_pos(stencil.sampleBufferBytes()), sample_nrm(stencil.sampleBufferBytes());
    Buffer visible[3] = {Buffer(4ull * p), Buffer(4ull * p), Buffer(4ull * p)};  // off, edge, full
    auto runOff = [&] {
        const Status s = hard.run(penumbra::SampleBufferInput{range(centres), normals}, p, light, draw);
        return s == Status::Ok ? stencil.resolve(AaMode::Off, {hard.stateBuffer().id(), 0, 4ull * p}, range(visible[0])) : s;
    };
    // Edge packs the flagged pixels' sub-samples after the centres, `budget` pixels' worth: the
    // hard pipeline runs P + budget N samples (full: P (1 + N)); with the provable stencil the
    // centres are all empty slots (it decided the unflagged pixels). Each run has a hard pipeline
    // whose light grid suits its sample count (afhGridSideForSamples; off: the view's size).
    auto runSamples = [&](penumbra::AliasFreeHardShadows& hp, ShadowEdgeStencil& st, AaMode mode, const Buffer& out,
                          uint32_t budget) {
        const uint32_t count = st.sampleCount(mode, budget);
        Status s = st.writeSampleBuffer(mode, range(sample_pos), range(sample_nrm), budget);
        if (s == Status::Ok) s = hp.run(penumbra::SampleBufferInput{range(sample_pos), range(sample_nrm)}, count, light, draw);
        return s == Status::Ok ? st.resolve(mode, {hp.stateBuffer().id(), 0, 4ull * count}, range(out), budget) : s;
    };
    auto gridFor = [&](uint64_t samples) {
        penumbra::AliasFreeHardOptions o = options;
        o.grid_width = o.grid_height = penumbra::afhGridSideForSamples(samples);
        return o;
    };
    penumbra::AliasFreeHardShadows hard_full(gridFor(all));
    hard_full.reserve(all);
    // The edge layout's budget: the frame's flagged count (an engine would take the last frame's
    // plus a margin); every flag, surface or not, takes a rank.
    auto budgetOf = [&](const std::vector<uint32_t>& ws) {
        uint32_t c = 0;
        for (uint32_t word : ws) c += (word & PENUMBRA_AA_FLAG) != 0;
        return c;
    };
    auto runStencil = [&](ShadowEdgeStencil& st) { return [&] { return st.run(range(centres), normals, v.view, light, casters); }; };
    auto flaggedCount = [&](const std::vector<uint32_t>& ws) {
        size_t c = 0;
        for (size_t i = 0; i < p; ++i) c += v.surface(i) && (ws[i] & PENUMBRA_AA_FLAG) != 0;
        return c;
    };
    auto differing = [&](const std::vector<float>& a, const std::vector<float>& b) {
        size_t c = 0;
        for (size_t i = 0; i < p; ++i) c += v.surface(i) && a[i] != b[i];
        return c;
    };

    AaStencilRun runs[kAaStencils];
    const double off_ms = timedFrame(runOff, "hard-shadow (--aa off)");
    if (off_ms < 0) return 1;
    const std::vector<float> vis_off = visible[0].download<float>();
    runs[main_kind].stencil_ms = timedFrame(runStencil(stencil), "shadow-edge stencil");
    if (runs[main_kind].stencil_ms < 0) return 1;
    runs[main_kind].words = stencil.readStencil();
    const uint32_t budget = budgetOf(runs[main_kind].words);
    const auto stencil_status = stencil.readStatus();
    // Edge's samples: the flagged pixels' sub-samples, plus every centre unless the stencil proved them.
    penumbra::AliasFreeHardShadows hard_edge(gridFor(uint64_t(budget) * n + (main_kind == 0 ? 0u : p)));
    hard_edge.reserve(all);
    const double edge_ms =
        timedFrame([&] { return runSamples(hard_edge, stencil, AaMode::Edge, visible[1], budget); }, "hard-shadow (--aa edge)");
    if (edge_ms < 0) return 1;
    const penumbra::AliasFreeHardFrame edge_frame = hard_edge.readFrame();
    const uint32_t budget_overflow = stencil.readStatus()[PENUMBRA_AA_STATUS_BUDGET_OVERFLOW];
    runs[main_kind].visible_edge = visible[1].download<float>();
    const double full_ms =
        timedFrame([&] { return runSamples(hard_full, stencil, AaMode::Full, visible[2], penumbra::kAaAllPixels); },
                   "hard-shadow (--aa full)");
    if (full_ms < 0) return 1;
    const penumbra::AliasFreeHardFrame full_frame = hard_full.readFrame();
    const std::vector<float> vis_full = visible[2].download<float>();
    const std::vector<glm::vec4> full_positions = sample_pos.download<glm::vec4>(0, all);
    // With --reference: the other stencils, run the same way (each stencil pass timed on its own).
    for (int k = 0; k < kAaStencils; ++k) {
        if (k == main_kind || !stencils[k]) continue;
        runs[k].stencil_ms = timedFrame(runStencil(*stencils[k]), kAaStencilNames[k]);
        if (runs[k].stencil_ms < 0) return 1;
        runs[k].words = stencils[k]->readStencil();
        if (runSamples(hard_edge, *stencils[k], AaMode::Edge, visible[1], budgetOf(runs[k].words)) != Status::Ok) return 1;
        runs[k].visible_edge = visible[1].download<float>();
    }
    for (AaStencilRun& r : runs)
        if (!r.words.empty()) r.flagged = flaggedCount(r.words);
    const std::vector<uint32_t>& words = runs[main_kind].words;
    const std::vector<float>& vis_edge = runs[main_kind].visible_edge;
    const size_t flagged = runs[main_kind].flagged;
    const size_t edge_vs_full = differing(vis_edge, vis_full);
    const double flagged_fraction = v.count ? double(flagged) / double(v.count) : 0.0;

    // --reference: the oracle on the very points the GPU tested (centres and sub-samples of --aa
    // full), and on 64 points per pixel (the rotated grid with N = 64, placed on the pixel's plane
    // as the sub-samples are) for the RMSE of off / edge / full.
    Json reference;
    double rmse_off = 0, rmse_full = 0;
    double reference_ms = 0;
    if (args.reference) {
        const auto t0 = std::chrono::steady_clock::now();
        penumbra::reference::VisibilityOptions vo;
        vo.coplanar_epsilon = options.coplanar_epsilon;
        const std::vector<uint8_t> lit = oracleLit(
            oracle, full_positions, v.faces, [&](size_t i) { return i < p ? i : (i - p) / n; }, light.light, vo,
            "oracle on the sub-samples");
        size_t edge_pixels = 0, tie_pixels = 0;
        for (AaStencilRun& r : runs) r.missed.assign(p, 0);
        for (size_t i = 0; i < p; ++i) {
            if (!v.surface(i)) continue;
            bool any_lit = lit[i] == 1, any_dark = lit[i] == 0, tie = lit[i] == 2;
            for (uint32_t k = 0; k < n; ++k) {
                const uint8_t s = lit[p + i * n + k];
                any_lit |= s == 1, any_dark |= s == 0, tie |= s == 2;
            }
            tie_pixels += tie;
            if (tie || !(any_lit && any_dark)) continue;
            ++edge_pixels;
            for (AaStencilRun& r : runs) {
                r.missed[i] = (r.words[i] & PENUMBRA_AA_FLAG) == 0;
                r.missed_count += r.missed[i];
            }
        }
        penumbra::AaPatternOptions dense;
        dense.samples = 64;
        const penumbra::AaFootprints ref64 = penumbra::aaFootprintsCpu(v.view, v.positions.data(), v.faces.data(), dense);
        const std::vector<uint8_t> lit64 =
            oracleLit(oracle, ref64.sub_samples, v.faces, [](size_t i) { return i / 64; }, light.light, vo, "oracle, 64 points per pixel");
        double sum_off = 0, sum_full = 0, sum_edge[kAaStencils] = {0, 0, 0};
        size_t compared = 0, ties64 = 0;
        for (size_t i = 0; i < p; ++i) {
            if (!v.surface(i)) continue;
            uint32_t lit_points = 0, points = 0;
            for (uint32_t k = 0; k < 64; ++k) {
                const uint8_t s = lit64[i * 64 + k];
                ties64 += s == 2;
                points += s != 2;
                lit_points += s == 1;
            }
            if (points == 0) continue;
            const double truth = double(lit_points) / double(points);
            ++compared;
            auto sq = [&](float x) { return (double(x) - truth) * (double(x) - truth); };
            sum_off += sq(vis_off[i]);
            sum_full += sq(vis_full[i]);
            for (int k = 0; k < kAaStencils; ++k) sum_edge[k] += sq(runs[k].visible_edge[i]);
        }
        auto rms = [&](double sum) { return compared ? std::sqrt(sum / double(compared)) : 0.0; };
        rmse_off = rms(sum_off);
        rmse_full = rms(sum_full);
        for (int k = 0; k < kAaStencils; ++k) runs[k].rmse_edge = rms(sum_edge[k]);
        reference = {{"rmse", args.aa == "edge" ? runs[main_kind].rmse_edge : rmse_full},
                     {"missed_edge_pixels", runs[main_kind].missed_count},
                     {"edge_pixels", edge_pixels},
                     {"tie_pixels", tie_pixels},
                     {"points", full_positions.size()},
                     {"compared_pixels", compared},
                     {"dense_points_per_pixel", 64},
                     {"dense_ties", ties64},
                     {"dense_stretched", ref64.stretched}};
        for (int k = 0; k < kAaStencils; ++k) reference[std::string(kAaStencilNames[k]) + "_missed"] = runs[k].missed_count;
        reference_ms = msSince(t0);
    }

    // Images: --aa's, the off | edge | full strip and the stencil overlay.
    const auto t0 = std::chrono::steady_clock::now();
    const int shade = args.shading == "bent" ? 1 : 0;
    penumbra::scene::ImageRgb8 images[3][2];
    shadeGpuImages(v, merged, light_pos, vis_off, images[0]);
    shadeGpuImages(v, merged, light_pos, vis_edge, images[1]);
    shadeGpuImages(v, merged, light_pos, vis_full, images[2]);
    penumbra::scene::writePng(args.out, images[args.aa == "edge" ? 1 : 2][shade]);
    const std::string compare_path = siblingPath(args.out, "_aa_compare"), stencil_path = siblingPath(args.out, "_aa_stencil");
    penumbra::scene::writePng(compare_path, sideBySide({&images[0][shade], &images[1][shade], &images[2][shade]}));
    writeStencilPng(stencil_path, images[1][shade], v, words, runs[main_kind].missed);
    const double shade_ms = msSince(t0);

    if (args.json) {
        Json j = reportHead(args, "hard");
        j["renderer"] = renderer;
        j["width"] = w;
        j["height"] = h;
        j["triangles"] = oracle.triangleCount();
        j["view_samples"] = v.count;
        j["light_samples"] = 1;
        j["light"] = {{"position", vec3Json(light_pos)}, {"radius", 0}};
        j["hard"] = {{"view_samples", args.view_samples}, {"coplanar_epsilon", options.coplanar_epsilon}};
        Json skips = Json::array();
        for (const std::string& s : args.skip_list)
            if (s != "cull") skips.push_back(s);
        j["skips"] = skips;
        const double stencil_ms = runs[main_kind].stencil_ms;
        Json aa = {{"mode", args.aa},
                   {"samples", n},
                   {"pattern", "rotated"},
                   {"stencil", kAaStencilNames[main_kind]},
                   {"flagged", flagged},
                   {"flagged_fraction", flagged_fraction},
                   {"extra_samples", uint64_t(flagged) * n},
                   {"seed_estimate", 1.0 + double(n) * flagged_fraction},
                   {"budget", budget},
                   {"budget_overflow", budget_overflow},
                   {"edge_vs_full_differing_pixels", edge_vs_full},
                   {"tested_samples", {{"off", v.count}, {"edge", edge_frame.statistics.listed_samples},
                                       {"full", full_frame.statistics.listed_samples}}},
                   {"light_grid", {{"off", {w, h}},  // each run's hard pipeline (W, H)
                                   {"edge", {hard_edge.options().grid_width, hard_edge.options().grid_height}},
                                   {"full", {hard_full.options().grid_width, hard_full.options().grid_height}}}},
                   {"stencil_pairs", stencil_status[PENUMBRA_AA_STATUS_PAIRS]},
                   {"stencil_exact_tests", stencil_status[PENUMBRA_AA_STATUS_EXACT]},
                   {"stencil_list_overflow", stencil_status[PENUMBRA_AA_STATUS_LIST_OVERFLOW]},
                   {"timings_ms", {{"off", off_ms},
                                   {"stencil", stencil_ms},
                                   {"edge_samples", edge_ms},
                                   {"edge", stencil_ms + edge_ms},
                                   {"full", full_ms},
                                   {"edge_samples_over_off", edge_ms / off_ms},
                                   {"edge_samples_over_seed_estimate", edge_ms / off_ms / (1.0 + double(n) * flagged_fraction)},
                                   {"edge_over_off", (stencil_ms + edge_ms) / off_ms},
                                   {"full_over_off", full_ms / off_ms}}}};
        if (args.reference) {
            aa["rmse"] = {{"off", rmse_off}, {"edge", runs[main_kind].rmse_edge}, {"full", rmse_full}};
            Json kinds;
            for (int k = 0; k < kAaStencils; ++k) {
                const AaStencilRun& r = runs[k];
                kinds[kAaStencilNames[k]] = {{"flagged", r.flagged},
                                             {"flagged_fraction", v.count ? double(r.flagged) / double(v.count) : 0.0},
                                             {"missed_edge_pixels", r.missed_count},
                                             {"edge_vs_full_differing_pixels", differing(r.visible_edge, vis_full)},
                                             {"rmse_edge", r.rmse_edge},
                                             {"stencil_ms", r.stencil_ms}};
            }
            aa["stencils"] = kinds;
            j["reference"] = reference;
        }
        j["aa"] = aa;
        j["timings_ms"] = {{"load", load_ms},
                           {"gbuffer", v.ms},
                           {"aa_frames", off_ms + runs[main_kind].stencil_ms + edge_ms + full_ms},
                           {"reference", reference_ms},
                           {"shade_and_write", shade_ms},
                           {"total", msSince(t_start)}};
        j["out"] = args.out;
        j["aa_compare"] = compare_path;
        j["aa_stencil"] = stencil_path;
        printReport(j);
    } else {
        std::printf("%s (hard, --aa %s, %ux %s stencil, %s): %zu of %zu pixels flagged (%.1f%%), edge vs full: %zu pixels differ; "
                    "%.1f ms off, %.1f ms stencil + %.1f ms edge, %.1f ms full -> %s\n",
                    args.scene.c_str(), args.aa.c_str(), n, kAaStencilNames[main_kind], renderer.c_str(), flagged, v.count,
                    100.0 * flagged_fraction, edge_vs_full, off_ms, runs[main_kind].stencil_ms, edge_ms, full_ms, args.out.c_str());
        if (args.reference) {
            std::printf("reference: %s edge pixels, missed: provable %zu, chebyshev %zu, chebyshev_inner %zu; RMSE vs 64 points "
                        "per pixel: off %.4f, edge %.4f, full %.4f\n",
                        reference["edge_pixels"].dump().c_str(), runs[0].missed_count, runs[1].missed_count,
                        runs[2].missed_count, rmse_off, runs[main_kind].rmse_edge, rmse_full);
        }
    }
    return 0;
}

// --mode hard: the GPU alias-free hard-shadow pipeline from the light's centre.
int runHard(const Args& args, const penumbra::scene::Scene& scene, const penumbra::reference::VisibilityOracle& oracle,
            const MergedScene& merged, const glm::dvec3& light_pos, double load_ms,
            std::chrono::steady_clock::time_point t_start) {
    penumbra::gl::HeadlessContext context;
    penumbra::scene::GpuScene gpu(scene);
    const uint32_t w = args.width, h = args.height;
    GpuViewSamples v(args, scene, gpu);
    if (args.aa != "off") return runHardAa(args, oracle, merged, light_pos, gpu, v, context.renderer(), load_ms, t_start);
    const double gbuffer_ms = v.ms;
    const bool depth_input = v.depth_input;
    const std::vector<glm::vec4>& positions = v.positions;
    const size_t view_samples = v.count;

    // The light must see the view samples: a starting frustum around their box, then §4.3 fitting.
    penumbra::SampleListsLight light;
    light.light = glm::vec4(glm::vec3(light_pos), 1.0f);
    light.view_projection = lightFrustumOrRefuse(light.light, v.lo, v.hi);
    // --skips: the options with the chosen skips on (all_off: every skip off, for --check-skips).
    auto makeOptions = [&](bool all_off) {
        penumbra::AliasFreeHardOptions o;
        o.grid_width = w;
        o.grid_height = h;
        o.count_work = true;
        if (depth_input) o.coplanar_epsilon = kDepthCoplanarEpsilon;
        o.scene_extent = oracle.sceneExtent();  // the oracle's E: far lights keep their shadows
        o.light_facing_only = !all_off && args.skip("cull");
        o.fit_frustum = !all_off && args.skip("fit");
        o.skip_shadowed = !all_off && args.skip("shadowed");
        o.clip_to_box = !all_off && args.skip("box");
        o.skip_empty_texels = !all_off && args.skip("empty");
        return o;
    };
    const penumbra::AliasFreeHardOptions options = makeOptions(false);
    penumbra::AliasFreeHardShadows pipeline(options);
    pipeline.reserve(w * h);
    auto draw = [&](penumbra::CasterClass cls) { gpu.drawClass(cls == penumbra::CasterClass::Closed); };
    const penumbra::scene::GBuffer& gbuffer = v.gbuffer;
    const penumbra::SampleBufferInput buffer_input{{gbuffer.positionBuffer().id(), 0, gbuffer.positionBuffer().size()},
                                                   {gbuffer.faceBuffer().id(), 0, gbuffer.faceBuffer().size()}};
    const penumbra::SampleDepthInput depth_samples{gbuffer.depthTexture(), gbuffer.faceTexture(), v.view};
    auto run = [&] {
        return depth_input ? pipeline.run(depth_samples, light, draw) : pipeline.run(buffer_input, w * h, light, draw);
    };
    if (depth_input) pipeline.validate(depth_samples);
    else pipeline.validate(buffer_input, w * h);
    const double shadows_ms = timedFrame(run, "hard-shadow");
    if (shadows_ms < 0) return 1;
    auto t0 = std::chrono::steady_clock::now();
    const penumbra::AliasFreeHardFrame frame = pipeline.readFrame();
    const std::vector<uint32_t> states = pipeline.stateBuffer().download<uint32_t>(0, size_t(w) * h);
    const size_t reconstructed_differently = v.adoptGpuPositions(pipeline.setup(), pipeline.buffers());

    // --check-skips: the same frame with every skip off, state by state.
    Json skips_check;
    if (args.check_skips) {
        penumbra::AliasFreeHardShadows off(makeOptions(true));
        off.reserve(w * h);
        auto run_off = [&] {
            return depth_input ? off.run(depth_samples, light, draw) : off.run(buffer_input, w * h, light, draw);
        };
        const double off_ms = timedFrame(run_off, "hard-shadow (skips off)");
        if (off_ms < 0) return 1;
        const penumbra::AliasFreeHardFrame off_frame = off.readFrame();
        const std::vector<uint32_t> off_states = off.stateBuffer().download<uint32_t>(0, size_t(w) * h);
        uint64_t mismatched = 0;
        for (size_t i = 0; i < states.size(); ++i) mismatched += states[i] != off_states[i];
        skips_check = {{"compared_words", states.size()},
                       {"mismatched_words", mismatched},
                       {"identical", mismatched == 0},
                       {"shadows_ms_on", shadows_ms},
                       {"shadows_ms_off", off_ms},
                       {"on", {{"fragments", frame.fragments},
                               {"tests", frame.tests},
                               {"triangles_emitted", frame.triangles_emitted},
                               {"tests_skipped", frame.tests_skipped},
                               {"fragments_skipped", frame.fragments_skipped},
                               {"triangles_culled", frame.triangles_culled}}},
                       {"off", {{"fragments", off_frame.fragments},
                                {"tests", off_frame.tests},
                                {"triangles_emitted", off_frame.triangles_emitted}}}};
        std::fprintf(stderr, "soft_shadows: --check-skips: %llu of %zu states differ with every skip off (%.1f ms on, %.1f ms off)\n",
                     static_cast<unsigned long long>(mismatched), states.size(), shadows_ms, off_ms);
    }

    // --reference: the oracle's verdict on the same float samples and light point; for depth input
    // also at the true surface points (the cost of depth reconstruction).
    penumbra::reference::HardComparison same, true_surface;
    double reference_ms = 0;
    if (args.reference) {
        t0 = std::chrono::steady_clock::now();
        std::fprintf(stderr, "soft_shadows: oracle check of %zu samples...\n", states.size());
        penumbra::reference::VisibilityOptions vo;
        vo.coplanar_epsilon = options.coplanar_epsilon;
        const penumbra::reference::HardLight hard_light = penumbra::reference::hardLight(light.light);
        same = penumbra::reference::compareHardStates(oracle, positions, states, hard_light, vo);
        if (depth_input) true_surface = penumbra::reference::compareHardStates(oracle, v.exact_positions, states, hard_light, vo);
        reference_ms = msSince(t0);
    }

    // Shade: direct light (bent or Phong) with the hard visibility.
    t0 = std::chrono::steady_clock::now();
    size_t shadowed = 0;
    std::vector<float> visible(states.size());
    for (size_t i = 0; i < states.size(); ++i) {
        visible[i] = states[i] == PENUMBRA_AFH_LIT ? 1.0f : 0.0f;
        shadowed += v.surface(i) && states[i] == PENUMBRA_AFH_SHADOWED;
    }
    penumbra::scene::ImageRgb8 images[2];  // [0] Phong, [1] bent
    shadeGpuImages(v, merged, light_pos, visible, images);
    penumbra::scene::writePng(args.out, images[args.shading == "bent" ? 1 : 0]);
    if (args.compare_shading) writeShadingCompare(args.out, images[0], images[1]);
    const double shade_ms = msSince(t0);
    const double total_ms = msSince(t_start);
    if (args.json) {
        Json j = reportHead(args, "hard");
        j["renderer"] = context.renderer();
        j["width"] = w;
        j["height"] = h;
        j["triangles"] = oracle.triangleCount();
        j["view_samples"] = view_samples;
        j["light_samples"] = 1;
        j["light"] = {{"position", vec3Json(light_pos)}, {"radius", 0}};
        j["hard"] = {{"tested", static_cast<size_t>(frame.statistics.listed_samples)},
                     {"shadowed", shadowed},
                     {"passes", frame.passes},
                     {"max_list_length", frame.statistics.max_list_length},
                     {"occupancy", frame.statistics.occupancy()},
                     {"fragments", frame.fragments},
                     {"tests", frame.tests},
                     {"triangles_emitted", frame.triangles_emitted},
                     {"overflow", frame.overflow},
                     {"tests_skipped", frame.tests_skipped},
                     {"fragments_skipped", frame.fragments_skipped},
                     {"triangles_culled", frame.triangles_culled},
                     {"view_samples", args.view_samples},
                     {"coplanar_epsilon", options.coplanar_epsilon}};
        j["skips"] = args.skip_list;
        if (args.check_skips) j["skips_check"] = skips_check;
        if (args.reference) {
            j["reference"] = {{"samples", same.samples}, {"mismatched", same.mismatched}, {"ties", same.ties}};
            if (depth_input) {
                j["reference"]["gpu_reconstruction_differs"] = reconstructed_differently;
                j["reference"]["true_surface"] = {{"samples", true_surface.samples},
                                                  {"mismatched", true_surface.mismatched},
                                                  {"ties", true_surface.ties}};
            }
        }
        j["timings_ms"] = {{"load", load_ms},        {"gbuffer", gbuffer_ms},        {"shadows", shadows_ms},
                           {"reference", reference_ms}, {"shade_and_write", shade_ms}, {"total", total_ms}};
        j["out"] = args.out;
        if (args.compare_shading) j["shading_compare"] = shadingComparePath(args.out);
        printReport(j);
    } else {
        std::printf("%s (hard, %s): %zu triangles, %zu samples tested, %zu shadowed, %.1f ms shadows -> %s\n",
                    args.scene.c_str(), context.renderer().c_str(), oracle.triangleCount(),
                    static_cast<size_t>(frame.statistics.listed_samples), shadowed, shadows_ms, args.out.c_str());
        if (args.reference) {
            std::printf("reference: %zu mismatched, %zu ties of %zu\n", same.mismatched, same.ties, same.samples);
            if (depth_input) {
                std::printf("true surface: %zu of %zu disagree (depth reconstruction)\n", true_surface.mismatched,
                            true_surface.samples);
            }
        }
    }
    return checksVerdict("hard", args.check_skips ? skips_check["mismatched_words"].get<uint64_t>() : 0,
                         args.reference ? same.mismatched : 0, "view samples");
}

/// Heat map of |a - b| per pixel (visible fractions; rows flipped as the shaded images): black
/// background, dark grey where they agree exactly, red → yellow → white up to `scale` and beyond.
void writeErrorPng(const std::string& path, const GpuViewSamples& v, const std::vector<float>& a, const std::vector<float>& b,
                   float scale) {
    const uint32_t w = v.view.width, h = v.view.height;
    penumbra::scene::ImageRgb8 image;
    image.width = w;
    image.height = h;
    image.pixels.assign(size_t(w) * h * 3, 0);
    for (uint32_t y = 0; y < h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            glm::vec3 c(0.0f);
            if (v.surface(i)) {
                const float e = std::fabs(a[i] - b[i]);
                if (e == 0.0f) {
                    c = glm::vec3(0.16f, 0.16f, 0.19f);
                } else {
                    const float t = std::min(1.0f, e / scale);  // small errors still show: red from the first bit
                    c = t < 0.5f ? glm::vec3(0.55f + 0.9f * t, 1.6f * t, 0.0f) : glm::vec3(1.0f, 0.8f + 0.4f * (t - 0.5f), 2.0f * (t - 0.5f));
                }
            }
            const size_t o = (size_t(h - 1 - y) * w + x) * 3;
            for (int k = 0; k < 3; ++k) image.pixels[o + k] = static_cast<uint8_t>(std::lround(255.0f * std::clamp(c[k], 0.0f, 1.0f)));
        }
    }
    penumbra::scene::writePng(path, image);
}

// --mode soft: the GPU sample-based soft-shadow pipeline (sintorn2008 §4): view samples from the
// G-buffer (or the depth buffer), lists, influence regions, LUT masks, resolve.
int runSoft(const Args& args, const penumbra::scene::Scene& scene, const penumbra::reference::VisibilityOracle& oracle,
            const MergedScene& merged, const glm::dvec3& light_pos, double light_radius, double load_ms,
            std::chrono::steady_clock::time_point t_start) {
    penumbra::gl::HeadlessContext context;
    penumbra::scene::GpuScene gpu(scene);
    const uint32_t w = args.width, h = args.height, n = args.samples, k = args.sets;
    GpuViewSamples v(args, scene, gpu);
    penumbra::SoftMode mode = args.lut == "exact" ? penumbra::SoftMode::Exact
                                    : args.lut == "lut" ? penumbra::SoftMode::Lut
                                                        : penumbra::SoftMode::Brute;

    // Light samples: K sets of N, one set and one of R rotation steps chosen per pixel
    // (sampleBasedSoftSelection; the oracle gets each pixel's rotated samples).
    auto t0 = std::chrono::steady_clock::now();
    penumbra::Light light;
    light.center = light_pos;
    light.size = glm::dvec3(light_radius);
    penumbra::LightSampleOptions sample_options;
    sample_options.count = n;
    sample_options.sets = k;
    const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, sample_options);
    const uint32_t rotations = args.rotations;
    const std::vector<glm::dvec4> sample_table = penumbra::sampleBasedSoftSampleTable(sets, rotations);
    std::vector<uint32_t> pixel_sets(size_t(w) * h);
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
            pixel_sets[size_t(y) * w + x] = penumbra::sampleBasedSoftSelection(x, y, 0, k, rotations);

    // The light grid: a frustum from the light centre around the view samples, cropped to them by
    // the §4.3 fit (the sample-list block's CPU twin, on the very floats the GPU tests: an engine
    // would take last frame's GPU fit), its far plane just beyond the farthest one. The influence
    // regions are built on this grid on the host.
    penumbra::SampleListsLight fit_light;
    fit_light.light = glm::vec4(glm::vec3(light_pos), 1.0f);
    fit_light.view_projection = lightFrustumOrRefuse(fit_light.light, v.lo, v.hi);
    penumbra::SampleListsOptions fit_options;
    fit_options.cull_back_facing = false;  // as the soft pipeline builds its lists
    fit_options.depth_range = penumbra::LightDepthRange::Unclipped;
    const penumbra::LightFrustumFit fit = penumbra::fitLightFrustumCpu(
        penumbra::sampleListsSetup(args.grid, args.grid, w * h), fit_light, v.positions.data(), nullptr, fit_options);
    glm::dvec3 box_lo(std::numeric_limits<double>::infinity()), box_hi(-std::numeric_limits<double>::infinity());
    for (const glm::vec4& p : v.positions) {
        if (p.w == 0.0f) continue;
        box_lo = glm::min(box_lo, glm::dvec3(p));
        box_hi = glm::max(box_hi, glm::dvec3(p));
    }
    const auto [scene_lo, scene_hi] = sceneBounds(scene);
    box_lo = glm::min(box_lo, scene_lo);
    box_hi = glm::max(box_hi, scene_hi);
    // The grid for a set of skips: fitted (skip "fit") or the frustum around the view samples' box
    // it starts from (what a renderer without the §4.3 fit would use); regions cut by their
    // caster's plane with skip "cut".
    struct LightGrid {
        glm::mat4 vp{1.0f};
        penumbra::InfluenceRegionSetup influence;
    };
    auto lightGrid = [&](bool fit_on, bool cut_on) {
        LightGrid g;
        g.vp = fit_on && fit.valid ? fit.view_projection : fit_light.view_projection;
        double far_depth = 0.0;
        for (const glm::vec4& p : v.positions)
            if (p.w != 0.0f) far_depth = std::max(far_depth, double((g.vp * glm::vec4(glm::vec3(p), 1.0f)).w));
        if (!(far_depth > 0.0)) return g;
        penumbra::InfluenceRegionOptions influence_options;
        influence_options.grid_width = influence_options.grid_height = int(args.grid);
        influence_options.far_plane = penumbra::influenceFarPlaneAtDepth(g.vp, far_depth * 1.01 + 1e-3);
        influence_options.cut_by_supporting_plane = cut_on;
        g.influence = penumbra::influenceRegionSetup(light, g.vp, influence_options);
        return g;
    };
    const LightGrid grid = lightGrid(args.skip("fit"), args.skip("cut"));
    if (grid.influence.width() == 0) {
        std::fprintf(stderr, "soft_shadows: no view sample in front of the light\n");
        return 1;
    }
    const glm::mat4& vp = grid.vp;
    const penumbra::InfluenceRegionSetup& influence = grid.influence;

    // --skips: the options with the chosen skips on (all_off: every skip off, for --check-skips).
    auto makeOptions = [&](bool all_off) {
        penumbra::SampleBasedSoftGpuOptions o;
        o.mode = mode;
        o.grid_width = o.grid_height = args.grid;
        o.rotations = rotations;
        o.timings = true;
        // The coplanar rule of the hard pipeline: above float rounding of surface points (1e-7) or
        // of positions rebuilt from a 32-bit depth buffer (kDepthCoplanarEpsilon).
        o.oracle.coplanar_epsilon = v.depth_input ? kDepthCoplanarEpsilon : 1e-7;
        o.scene_extent = oracle.sceneExtent();  // the oracle's E: far lights keep their shadows
        o.skips.empty_blocks = !all_off && args.skip("empty");
        o.skips.closed_casters = !all_off && args.skip("cull");
        o.skips.plane_cut = !all_off && args.skip("cut");
        o.skips.silhouettes = !all_off && args.skip("silhouette");
        o.skips.wedges = !all_off && args.skip("wedge");
        return o;
    };
    penumbra::SampleBasedSoftGpuOptions options = makeOptions(false);

    // The LUT (sintorn2008 §4.2), generated on the GPU; certified for Exact, with the tolerance
    // that lets Exact prove pairs at this coplanar epsilon (sampleBasedSoftLutTolerance). A light
    // that is tiny or far for the scene needs a tolerance past what a LUT can certify (1e-2): the
    // LUT could vouch for no bit, so Exact tests every light sample (Brute: the same exact bits).
    double lut_tolerance = 0;
    bool exact_by_brute = false;
    if (mode == penumbra::SoftMode::Exact) {
        lut_tolerance = penumbra::sampleBasedSoftLutTolerance(options, sets.frame, box_lo, box_hi);
        if (lut_tolerance > kMaxLutTolerance) {
            std::fprintf(stderr, "soft_shadows: --lut exact: this light (radius %g, %g from the scene's box) needs a LUT "
                                 "tolerance of %.3g, past the %.0e a LUT can certify; every light sample is tested "
                                 "(as --lut brute: the same exact bits, slower)\n",
                         light_radius, glm::length(light_pos - glm::clamp(light_pos, box_lo, box_hi)), lut_tolerance,
                         kMaxLutTolerance);
            mode = penumbra::SoftMode::Brute;
            options = makeOptions(false);
            exact_by_brute = true;
        }
    }
    penumbra::LightLutOptions lut_options;
    lut_options.resolution = args.lut_res;
    lut_options.certified = mode == penumbra::SoftMode::Exact;
    if (mode == penumbra::SoftMode::Exact) lut_options.tolerance = lut_tolerance;
    std::unique_ptr<penumbra::LightLutSetup> lut;
    penumbra::gl::Buffer lut_buffer;
    penumbra::BufferRange lut_table;
    if (mode != penumbra::SoftMode::Brute) {
        lut = std::make_unique<penumbra::LightLutSetup>(penumbra::lightLutSetup(sets, lut_options));
        lut_buffer = penumbra::gl::Buffer(lut->tableBytes());
        lut_table = {lut_buffer.id(), 0, lut->tableBytes()};
        std::fprintf(stderr, "soft_shadows: generating the %s light-sample LUT on the GPU: %u^3 texels per table, %s...\n",
                     lut_options.certified ? "certified" : "seed's", args.lut_res, gib(double(lut->tableBytes())).c_str());
        const auto t_lut = std::chrono::steady_clock::now();
        penumbra::LightLutGenerator generator;
        generator.reserve(*lut);
        generator.validate(*lut, lut_table);
        if (generator.generate(*lut, lut_table) != penumbra::Status::Ok) {
            std::fprintf(stderr, "soft_shadows: the LUT generator refused the table\n");
            return 1;
        }
        glFinish();
        std::fprintf(stderr, "soft_shadows: LUT done in %.1f s\n", msSince(t_lut) * 1e-3);
    }
    const double lut_ms = msSince(t0);

    // The pipeline: load time (compile, reserve, validate), then one warm-up and one timed frame.
    penumbra::SampleBasedSoftShadows pipeline(options, sets, lut.get(), influence, vp);
    pipeline.reserve(w * h);
    // Allocated once: --frames uploads each frame's selection words into it.
    penumbra::gl::Buffer sets_buffer = penumbra::gl::Buffer::fromVector(pixel_sets);
    const penumbra::SbsFrameBuffers frame_buffers{{sets_buffer.id(), 0, sets_buffer.size()}, {}, {}};
    const penumbra::scene::GBuffer& gbuffer = v.gbuffer;
    const penumbra::SampleBufferInput buffer_input{{gbuffer.positionBuffer().id(), 0, gbuffer.positionBuffer().size()}, {}};
    const penumbra::SampleDepthInput depth_samples{gbuffer.depthTexture(), 0, v.view};
    const auto draw = [&](penumbra::CasterClass c) { gpu.drawClass(c == penumbra::CasterClass::Closed); };
    const auto draw_adjacency = [&] { gpu.drawAdjacency(); };
    auto run = [&] {
        return v.depth_input ? pipeline.run(depth_samples, lut_table, draw, frame_buffers, draw_adjacency)
                             : pipeline.run(buffer_input, w * h, lut_table, draw, frame_buffers, draw_adjacency);
    };
    if (v.depth_input) pipeline.validate(depth_samples, lut_table, frame_buffers);
    else pipeline.validate(buffer_input, w * h, lut_table, frame_buffers);
    std::fprintf(stderr, "soft_shadows: GPU soft shadows (%s, N = %u, %u x %u samples, grid %u^2)...\n", args.lut.c_str(), n, w,
                 h, args.grid);
    const double shadows_ms = timedFrame(run, "soft-shadow");
    if (shadows_ms < 0) return 1;
    const penumbra::SampleBasedSoftFrame frame = pipeline.readFrame();
    std::vector<float> gpu_visibility = pipeline.readVisibility();  // frame 0's; --frames: the last frame's
    const size_t reconstructed_differently = v.adoptGpuPositions(pipeline.setup(), pipeline.buffers());
    const uint32_t words = pipeline.wordsPerSample();
    // SoftSkips::silhouettes: light texels inside some potential silhouette's region.
    uint64_t penumbra_texels = 0;
    for (uint32_t m : pipeline.readMarks()) penumbra_texels += m != 0;

    // --check-skips: the same frame (frame 0's selection words) with every skip off: unfitted grid,
    // uncut regions, no culling, no cut, every fragment set up; masks word for word.
    Json skips_check;
    if (args.check_skips) {
        std::vector<uint32_t> masks_on = pipeline.readMasks();
        if (faultInjected("skips") && !masks_on.empty()) masks_on[0] ^= 1u;
        const LightGrid off_grid = lightGrid(false, false);
        penumbra::SampleBasedSoftShadows off(makeOptions(true), sets, lut.get(), off_grid.influence, off_grid.vp);
        off.reserve(w * h);
        auto run_off = [&] {
            return v.depth_input ? off.run(depth_samples, lut_table, draw, frame_buffers)
                                 : off.run(buffer_input, w * h, lut_table, draw, frame_buffers);
        };
        const double off_ms = timedFrame(run_off, "soft-shadow (skips off)");
        if (off_ms < 0) return 1;
        const penumbra::SampleBasedSoftFrame off_frame = off.readFrame();
        const std::vector<uint32_t> masks_off = off.readMasks();
        uint64_t mismatched = 0, mismatched_samples = 0;
        for (size_t i = 0; i < size_t(w) * h; ++i) {
            uint64_t wrong = 0;
            for (uint32_t k2 = 0; k2 < words; ++k2) wrong += masks_on[i * words + k2] != masks_off[i * words + k2];
            mismatched += wrong;
            mismatched_samples += wrong != 0;
        }
        auto work = [](const penumbra::SampleBasedSoftFrame& f) {
            return Json{{"fragments", f.fragments},         {"fragments_skipped", f.fragments_skipped},
                        {"pairs", f.pairs},                 {"pairs_cut", f.pairs_cut},
                        {"triangles_culled", f.triangles_culled}, {"exact_tests", f.exact_tests},
                        {"pairs_hard", f.pairs_hard},         {"pairs_recovered", f.pairs_recovered},
                        {"tests_skipped", f.pairs_cut + f.pairs_hard},
                        {"max_list_length", f.statistics.max_list_length}};
        };
        skips_check = {{"compared_words", masks_on.size()},
                       {"mismatched_words", mismatched},
                       {"mismatched_view_samples", mismatched_samples},
                       {"identical", mismatched == 0},
                       {"shadows_ms_on", shadows_ms},
                       {"shadows_ms_off", off_ms},
                       {"on", work(frame)},
                       {"off", work(off_frame)}};
        std::fprintf(stderr, "soft_shadows: --check-skips: %llu of %zu mask words differ with every skip off (%.1f ms on, %.1f ms off)\n",
                     static_cast<unsigned long long>(mismatched), masks_on.size(), shadows_ms, off_ms);
    }
    // GL_TIME_ELAPSED per stage: trusted on a GPU renderer where the stages add up to a plausible
    // share of the wall time (llvmpipe's queries leave out compute work: HeadlessContext::cpuRenderer()).
    const double stage_ms[3] = {frame.lists_ns * 1e-6, frame.light_pass_ns * 1e-6, frame.resolve_ns * 1e-6};
    const double stages_ms = stage_ms[0] + stage_ms[1] + stage_ms[2];
    const bool timers_measure = !context.cpuRenderer() && stages_ms >= 0.05 * shadows_ms && stages_ms <= 1.5 * shadows_ms;

    // Per pixel visible fraction (untested samples: lit, counted).
    size_t untested = 0, tested = 0;
    std::vector<float> visible(size_t(w) * h, 1.0f);
    double visible_sum = 0;
    for (size_t i = 0; i < visible.size(); ++i) {
        if (!v.surface(i)) continue;
        if (gpu_visibility[i] < 0.0f) {
            ++untested;
            continue;
        }
        ++tested;
        visible[i] = gpu_visibility[i];
        visible_sum += visible[i];
    }

    // --frames F > 1: temporal accumulation (sintorn2008 §4.2, Fig. 7). Frame f gives every pixel a
    // fresh selection word (set and rotation step: sampleBasedSoftSelection(x, y, f, K, R)), uploaded
    // into the sets buffer allocated at load time, then one run; each surface pixel keeps the running
    // average of its tested visibilities. After every frame: the RMSE of that average against an
    // oracle image of --frames-reference samples on the same float view samples. Frame 0 is the
    // timed frame above, so after it the average is the single-frame image.
    Json temporal_json;
    std::vector<float> frame_visible;  // the last frame's own visibility (what --reference checks)
    if (args.frames > 1) {
        t0 = std::chrono::steady_clock::now();
        penumbra::reference::VisibilityOptions vo;
        vo.coplanar_epsilon = options.oracle.coplanar_epsilon;
        std::vector<size_t> members;
        std::vector<glm::dvec3> points;
        for (size_t i = 0; i < visible.size(); ++i) {
            if (!v.surface(i) || v.positions[i].w == 0.0f) continue;
            members.push_back(i);
            points.emplace_back(v.positions[i]);
        }
        const std::vector<glm::dvec3> reference_samples =
            penumbra::reference::sphereLightSamples(light_pos, light_radius, args.frames_reference, 7);
        std::vector<double> truth(members.size());
        {
            const penumbra::reference::VisibilityResult image =
                evaluateWithProgress(oracle, points, reference_samples, vo, "reference image");
            for (size_t m = 0; m < members.size(); ++m) truth[m] = image.visibleFraction(m);
        }
        const double reference_image_ms = msSince(t0);

        std::vector<double> sum(visible.size(), 0.0);
        std::vector<uint32_t> count(visible.size(), 0u);
        Json rmse = Json::array(), rmse_scaled = Json::array(), frame_ms = Json::array();
        for (uint32_t f = 0; f < args.frames; ++f) {
            if (f > 0) {
                for (uint32_t y = 0; y < h; ++y)
                    for (uint32_t x = 0; x < w; ++x)
                        pixel_sets[size_t(y) * w + x] = penumbra::sampleBasedSoftSelection(x, y, f, k, rotations);
                sets_buffer.upload(0, pixel_sets.data(), pixel_sets.size() * sizeof(uint32_t));
                const auto t_frame = std::chrono::steady_clock::now();
                const penumbra::Status status = run();
                glFinish();
                const double ms = msSince(t_frame);
                if (status != penumbra::Status::Ok) {
                    std::fprintf(stderr, "soft_shadows: the soft-shadow pipeline returned '%s' in frame %u\n",
                                 penumbra::statusName(status), f + 1);
                    return 1;
                }
                frame_ms.push_back(ms);
                gpu_visibility = pipeline.readVisibility();
            } else {
                frame_ms.push_back(shadows_ms);
            }
            for (size_t i = 0; i < visible.size(); ++i) {
                if (!v.surface(i) || gpu_visibility[i] < 0.0f) continue;
                sum[i] += gpu_visibility[i];
                ++count[i];
            }
            double squares = 0;
            size_t compared = 0;
            for (size_t m = 0; m < members.size(); ++m) {
                const size_t i = members[m];
                if (count[i] == 0) continue;
                const double e = sum[i] / count[i] - truth[m];
                squares += e * e;
                ++compared;
            }
            const double value = compared ? std::sqrt(squares / double(compared)) : 0.0;
            rmse.push_back(value);
            rmse_scaled.push_back(value * std::sqrt(double(f + 1)));
            std::fprintf(stderr, "soft_shadows: frame %u/%u: visibility RMSE %.5f vs %u-sample oracle (x sqrt(frames) = %.4f)\n",
                         f + 1, args.frames, value, args.frames_reference, value * std::sqrt(double(f + 1)));
        }
        frame_visible.assign(visible.size(), 1.0f);
        visible_sum = 0;
        for (size_t i = 0; i < visible.size(); ++i) {
            if (v.surface(i) && gpu_visibility[i] >= 0.0f) frame_visible[i] = gpu_visibility[i];
            if (count[i] == 0) continue;
            visible[i] = float(sum[i] / count[i]);
            visible_sum += visible[i];
        }
        temporal_json = {{"frames", args.frames},
                         {"sets", k},
                         {"rotations", rotations},
                         {"samples_per_frame", n},
                         {"reference_samples", args.frames_reference},
                         {"rmse", rmse},
                         {"rmse_times_sqrt_frames", rmse_scaled},
                         {"frame_ms", frame_ms},
                         {"reference_ms", reference_image_ms}};
    }
    // --reference checks one frame's masks: the only one, or with --frames the last.
    const std::vector<float>& checked_visible = args.frames > 1 ? frame_visible : visible;

    // --reference: the oracle on the same float view samples, each with the same light-sample set
    // (grouped by set), bit by bit; ties apart. With --frames: the last frame's masks, selection
    // words (pixel_sets) and visibility.
    Json reference_json;
    std::vector<float> oracle_visible;
    double reference_ms = 0;
    if (args.reference) {
        t0 = std::chrono::steady_clock::now();
        std::vector<uint32_t> masks = pipeline.readMasks();
        if (faultInjected("reference"))
            for (size_t i = 0; i < masks.size(); i += words) masks[i] ^= 1u;
        penumbra::reference::VisibilityOptions vo;
        vo.coplanar_epsilon = options.oracle.coplanar_epsilon;
        vo.tie_epsilon = options.oracle.tie_epsilon;
        oracle_visible = checked_visible;
        uint64_t total_bits = 0, ties = 0, mismatched = 0, mismatched_samples = 0, compared = 0;
        double squares = 0;
        for (uint32_t g = 0; g < k * rotations; ++g) {
            const uint32_t word = (g / rotations) | (g % rotations) << 8;  // set, rotation step
            std::vector<size_t> members;
            std::vector<glm::dvec3> points;
            for (size_t i = 0; i < visible.size(); ++i) {
                if (!v.surface(i) || gpu_visibility[i] < 0.0f || pixel_sets[i] != word || v.positions[i].w == 0.0f) continue;
                members.push_back(i);
                points.emplace_back(v.positions[i]);
            }
            if (members.empty()) continue;
            const std::string what = "oracle check, group " + std::to_string(g + 1) + " of " + std::to_string(k * rotations);
            std::vector<glm::dvec3> samples;
            for (uint32_t i = 0; i < n; ++i) samples.emplace_back(sample_table[size_t(g) * n + i]);
            const penumbra::reference::VisibilityResult truth = evaluateWithProgress(oracle, points, samples, vo, what.c_str());
            for (size_t m = 0; m < members.size(); ++m) {
                const size_t i = members[m];
                uint64_t wrong = 0;
                for (uint32_t b = 0; b < n; ++b) {
                    ++total_bits;
                    if (truth.isTie(m, b)) {
                        ++ties;
                        continue;
                    }
                    wrong += ((masks[i * words + b / 32] >> (b % 32)) & 1u) != uint32_t(truth.isBlocked(m, b));
                }
                mismatched += wrong;
                mismatched_samples += wrong > 0;
                oracle_visible[i] = float(truth.visibleFraction(m));
                const double e = double(checked_visible[i]) - truth.visibleFraction(m);
                squares += e * e;
                ++compared;
            }
        }
        reference_ms = msSince(t0);
        const float error_scale = 0.1f;
        penumbra::scene::ImageRgb8 reference_images[2];
        shadeGpuImages(v, merged, light_pos, oracle_visible, reference_images);
        penumbra::scene::writePng(siblingPath(args.out, "_reference"), reference_images[args.shading == "bent" ? 1 : 0]);
        writeErrorPng(siblingPath(args.out, "_error"), v, checked_visible, oracle_visible, error_scale);
        reference_json = {{"mismatched_bits", mismatched},
                          {"total_bits", total_bits},
                          {"ties", ties},
                          {"visibility_rmse", compared ? std::sqrt(squares / double(compared)) : 0.0},
                          {"view_samples", compared},
                          {"mismatched_view_samples", mismatched_samples},
                          {"gpu_reconstruction_differs", reconstructed_differently},
                          {"png", siblingPath(args.out, "_reference")},
                          {"error_png", siblingPath(args.out, "_error")},
                          {"error_png_scale", error_scale}};
    }

    t0 = std::chrono::steady_clock::now();
    penumbra::scene::ImageRgb8 images[2];  // [0] Phong, [1] bent
    shadeGpuImages(v, merged, light_pos, visible, images);
    penumbra::scene::writePng(args.out, images[args.shading == "bent" ? 1 : 0]);
    if (args.compare_shading) writeShadingCompare(args.out, images[0], images[1]);
    const double shade_ms = msSince(t0);
    const double total_ms = msSince(t_start);
    const uint64_t pair_bits = frame.pairs * n;
    if (args.json) {
        Json j = reportHead(args, "soft");
        j["renderer"] = context.renderer();
        j["width"] = w;
        j["height"] = h;
        j["triangles"] = oracle.triangleCount();
        j["view_samples"] = v.count;
        j["light_samples"] = n;
        j["light_sample_sets"] = k;
        j["light_sample_rotations"] = rotations;
        j["light"] = {{"position", vec3Json(light_pos)}, {"radius", light_radius}};
        j["mean_visible_fraction"] = tested ? visible_sum / double(tested) : 0.0;
        j["soft"] = {{"lut", args.lut},
                     {"lut_res", args.lut_res},
                     {"lut_tolerance", lut_options.tolerance},
                     {"exact_by_brute", exact_by_brute},
                     {"lut_bytes", lut ? lut->tableBytes() : 0},
                     {"grid", args.grid},
                     {"view_samples", args.view_samples},
                     {"coplanar_epsilon", options.oracle.coplanar_epsilon},
                     {"tested", tested},
                     {"untested", untested},
                     {"passes", frame.passes},
                     {"max_list_length", frame.statistics.max_list_length},
                     {"occupancy", frame.statistics.occupancy()},
                     {"fragments", frame.fragments},
                     {"pairs", frame.pairs},
                     {"pairs_ignored", frame.pairs_ignored},
                     {"pairs_unproven", frame.pairs_unproven},
                     {"uncertain_bits", frame.uncertain_bits},
                     {"uncertain_fraction", pair_bits ? double(frame.uncertain_bits) / double(pair_bits) : 0.0},
                     {"exact_tests", frame.exact_tests},
                     {"overflow", frame.overflow},
                     {"fragments_skipped", frame.fragments_skipped},
                     {"triangles_culled", frame.triangles_culled},
                     {"pairs_cut", frame.pairs_cut},
                     {"pairs_hard", frame.pairs_hard},
                     {"pairs_recovered", frame.pairs_recovered},
                     {"pairs_front", frame.pairs_front},
                     {"pairs_wedged", frame.pairs_wedged},
                     {"tests_skipped", frame.pairs_cut + frame.pairs_hard + frame.pairs_wedged},
                     {"penumbra_texels", penumbra_texels}};
        j["skips"] = args.skip_list;
        if (args.check_skips) j["skips_check"] = skips_check;
        if (args.reference) j["reference"] = reference_json;
        if (args.frames > 1) j["temporal"] = temporal_json;
        j["timings_ms"] = {{"load", load_ms},
                           {"gbuffer", v.ms},
                           {"light_samples_and_lut", lut_ms},
                           {"shadows", shadows_ms},
                           {"gpu_timer", timers_measure ? "GL_TIME_ELAPSED" : "unmeasured"},
                           {"lists", stage_ms[0]},
                           {"light_pass", stage_ms[1]},
                           {"resolve", stage_ms[2]},
                           {"reference", reference_ms},
                           {"shade_and_write", shade_ms},
                           {"total", total_ms}};
        j["out"] = args.out;
        if (args.compare_shading) j["shading_compare"] = shadingComparePath(args.out);
        printReport(j);
    } else {
        std::printf("%s (soft %s, N = %u, %s): %zu triangles, %zu view samples, %.1f ms shadows", args.scene.c_str(),
                    args.lut.c_str(), n, context.renderer().c_str(), oracle.triangleCount(), v.count, shadows_ms);
        if (timers_measure) {
            std::printf(" (lists %.2f, light pass %.2f, resolve %.2f ms)", stage_ms[0], stage_ms[1], stage_ms[2]);
        } else {
            std::printf(" (per-stage GPU timers not measured by this driver)");
        }
        std::printf(" -> %s\n", args.out.c_str());
        if (args.reference) {
            std::printf("reference: %s mismatched bits of %s, %s ties, visibility RMSE %.3g -> %s, %s\n",
                        reference_json["mismatched_bits"].dump().c_str(), reference_json["total_bits"].dump().c_str(),
                        reference_json["ties"].dump().c_str(), reference_json["visibility_rmse"].get<double>(),
                        siblingPath(args.out, "_reference").c_str(), siblingPath(args.out, "_error").c_str());
        }
        if (args.frames > 1) {
            std::printf("temporal: %u frames, visibility RMSE %.5f -> %.5f vs %u-sample oracle\n", args.frames,
                        temporal_json["rmse"].front().get<double>(), temporal_json["rmse"].back().get<double>(),
                        args.frames_reference);
        }
    }
    const bool exact_mode = args.lut != "lut";  // exact and brute equal the oracle; lut is the seed's approximation
    return checksVerdict("soft", args.check_skips ? skips_check["mismatched_words"].get<uint64_t>() : 0,
                         args.reference && exact_mode ? reference_json["mismatched_bits"].get<uint64_t>() : 0, "shadow bits");
}

// --mode reference: soft shadows from the oracle, every (view sample, light sample) pair.
/// The CPU renderers' view samples: one primary ray per pixel through the oracle (double), the
/// hit point, its shading normal and triangle; receivers are the hit points in pixel order.
struct PrimaryHits {
    std::vector<int64_t> pixel_sample;  ///< per pixel: index into receivers, -1 for background
    std::vector<glm::dvec3> hit_point, hit_normal;
    std::vector<uint32_t> hit_triangle;
    std::vector<glm::dvec3> receivers;
    std::vector<uint32_t> receiver_pixel;  ///< per receiver: its pixel (row 0 at the top)
};

PrimaryHits primaryHits(const Args& args, const penumbra::scene::Scene& scene,
                        const penumbra::reference::VisibilityOracle& oracle, const MergedScene& merged) {
    const uint32_t w = args.width, h = args.height;
    const glm::dmat4 inv_view_proj =
        glm::inverse(glm::dmat4(scene.camera.projection(float(w) / float(h))) * glm::dmat4(scene.camera.view()));
    const size_t pixels = size_t(w) * h;
    PrimaryHits hits;
    hits.pixel_sample.assign(pixels, -1);
    hits.hit_normal.resize(pixels);
    hits.hit_triangle.resize(pixels);
    hits.hit_point.resize(pixels);
    const glm::dvec3 eye(scene.camera.eye);
    {
        Progress progress("primary rays", pixels);
        inChunks(pixels, w, progress, [&](size_t begin, size_t end) {
            parallelFor(begin, end, [&](size_t i) {
                const double x = (double(i % w) + 0.5) / w * 2.0 - 1.0;
                const double y = 1.0 - (double(i / w) + 0.5) / h * 2.0;  // row 0 is the top of the image
                glm::dvec4 far_point = inv_view_proj * glm::dvec4(x, y, 1.0, 1.0);
                glm::dvec3 dir = glm::normalize(glm::dvec3(far_point) / far_point.w - eye);
                penumbra::reference::Hit hit = oracle.closestHit(eye, dir, 0.0, 1e30);
                if (!hit.hit) return;
                const uint32_t* tri = &merged.indices[size_t(hit.triangle) * 3];
                const double u = hit.u, v = hit.v;
                glm::dvec3 n = (1.0 - u - v) * merged.normals[tri[0]] + u * merged.normals[tri[1]] + v * merged.normals[tri[2]];
                if (glm::dot(n, n) < 1e-20) {
                    n = glm::cross(merged.positions[tri[1]] - merged.positions[tri[0]],
                                   merged.positions[tri[2]] - merged.positions[tri[0]]);
                }
                n = glm::normalize(n);
                if (glm::dot(n, dir) > 0) n = -n;  // open meshes: shade the side we see
                hits.hit_point[i] = eye + hit.t * dir;
                hits.hit_normal[i] = n;
                hits.hit_triangle[i] = hit.triangle;
                hits.pixel_sample[i] = 0;
            });
        });
    }
    for (size_t i = 0; i < hits.pixel_sample.size(); ++i) {
        if (hits.pixel_sample[i] < 0) continue;
        hits.pixel_sample[i] = static_cast<int64_t>(hits.receivers.size());
        hits.receivers.push_back(hits.hit_point[i]);
        hits.receiver_pixel.push_back(static_cast<uint32_t>(i));
    }
    return hits;
}

/// Direct light (bent or Phong) times each receiver's visible fraction, sRGB, written to args.out
/// (and the Phong/bent comparison when asked). Returns the sum of the visible fractions.
double shadeAndWrite(const Args& args, const MergedScene& merged, const glm::dvec3& light_pos, const PrimaryHits& hits,
                     const std::vector<double>& visible) {
    const size_t pixels = hits.pixel_sample.size();
    const DirectShading direct(merged, light_pos);
    penumbra::scene::ImageRgb8 images[2];  // [0] Phong, [1] bent
    for (auto& image : images) {
        image.width = args.width;
        image.height = args.height;
        image.pixels.assign(pixels * 3, 0);
    }
    const glm::dvec3 albedo[2] = {{0.75, 0.75, 0.72}, {0.85, 0.45, 0.2}};
    const glm::dvec3 sky(0.08, 0.09, 0.12);
    double lit_sum = 0;
    for (size_t i = 0; i < pixels; ++i) {
        glm::dvec3 c[2] = {sky, sky};
        if (hits.pixel_sample[i] >= 0) {
            const size_t r = static_cast<size_t>(hits.pixel_sample[i]);
            const double vis = visible[r];
            lit_sum += vis;
            const glm::dvec3 l = glm::normalize(light_pos - hits.hit_point[i]);
            for (int bent = 0; bent < 2; ++bent) {
                const double light =
                    direct.direct(bent == 1, hits.hit_triangle[i], hits.hit_point[i], hits.hit_normal[i], l);
                c[bent] = albedo[merged.material[hits.hit_triangle[i]]] * (0.12 + 0.88 * light * vis);
            }
        }
        for (int b = 0; b < 2; ++b)
            for (int k = 0; k < 3; ++k) images[b].pixels[i * 3 + k] = penumbra::scene::linearToSrgb8(float(c[b][k]));
    }
    penumbra::scene::writePng(args.out, images[args.shading == "bent" ? 1 : 0]);
    if (args.compare_shading) writeShadingCompare(args.out, images[0], images[1]);
    return lit_sum;
}

int runHpc(const Args& args, const penumbra::scene::Scene& scene, const penumbra::reference::VisibilityOracle& oracle,
           const MergedScene& merged, const glm::dvec3& light_pos, double light_radius, double load_ms,
           std::chrono::steady_clock::time_point t_start) {
    auto t0 = std::chrono::steady_clock::now();
    const PrimaryHits hits = primaryHits(args, scene, oracle, merged);
    const std::vector<glm::dvec3>& receivers = hits.receivers;
    const double primary_ms = msSince(t0);

    // ---- the light: a sphere, K sets of N samples, set per pixel (laine2005 §3.4) ----
    penumbra::Light light;
    light.center = light_pos;
    light.size = glm::dvec3(light_radius);
    penumbra::LightSampleOptions sample_options;
    sample_options.count = args.samples;
    sample_options.sets = args.sets;
    sample_options.seed = 1;
    const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, sample_options);
    std::vector<uint32_t> receiver_sets(receivers.size());
    for (size_t r = 0; r < receivers.size(); ++r) {
        const uint32_t pixel = hits.receiver_pixel[r];
        receiver_sets[r] = penumbra::lightSampleSet(pixel % args.width, pixel / args.width, 0, args.sets);
    }

    // ---- penumbra casting: every triangle streamed once, no scene hierarchy ----
    t0 = std::chrono::steady_clock::now();
    penumbra::PenumbraCastingOptions options;
    options.scene_extent = oracle.sceneExtent();  // the oracle's E: far lights keep their shadows
    auto last_progress = std::chrono::steady_clock::now();
    options.progress = [&last_progress, t0](double fraction) {  // every 3 s at most, on stderr
        const auto now = std::chrono::steady_clock::now();
        if (now - last_progress >= std::chrono::seconds(3)) {
            last_progress = now;
            std::fprintf(stderr, "soft_shadows: penumbra casting %5.1f%% (%.0f s)\n", 100.0 * fraction, msSince(t0) / 1000.0);
        }
        return true;
    };
    size_t next = 0;
    const penumbra::PenumbraCastingResult result = penumbra::penumbraCast(
        receivers, light, sets,
        [&](glm::dvec3& a, glm::dvec3& b, glm::dvec3& c) {
            if (next + 3 > merged.indices.size()) return false;
            a = merged.positions[merged.indices[next]];
            b = merged.positions[merged.indices[next + 1]];
            c = merged.positions[merged.indices[next + 2]];
            next += 3;
            return true;
        },
        options, receiver_sets);
    const double casting_ms = msSince(t0);
    std::vector<double> visible(receivers.size());
    for (size_t r = 0; r < receivers.size(); ++r) visible[r] = result.visibleFraction(r);

    // ---- --reference: the oracle on the same receivers and each receiver's own sample set ----
    Json reference_json;
    double reference_ms = 0.0;
    if (args.reference) {
        t0 = std::chrono::steady_clock::now();
        uint64_t mismatched = 0, ties = 0, total = 0;
        const size_t words = result.words_per_receiver;
        for (uint32_t set = 0; set < sets.sets(); ++set) {
            std::vector<size_t> members;
            std::vector<glm::dvec3> points;
            for (size_t r = 0; r < receivers.size(); ++r) {
                if (receiver_sets[r] != set) continue;
                members.push_back(r);
                points.push_back(receivers[r]);
            }
            if (members.empty()) continue;
            const std::vector<glm::dvec3> samples(sets.worldSet(set), sets.worldSet(set) + sets.count());
            const std::string what = "oracle (set " + std::to_string(set + 1) + " of " + std::to_string(sets.sets()) + ")";
            const penumbra::reference::VisibilityResult truth = evaluateWithProgress(oracle, points, samples, {}, what.c_str());
            for (size_t k = 0; k < members.size(); ++k) {
                for (size_t w = 0; w < words; ++w) {
                    const uint32_t tie = truth.ties[k * truth.words_per_receiver + w];
                    const uint32_t want = truth.blocked[k * truth.words_per_receiver + w];
                    mismatched += uint64_t(__builtin_popcount((result.blocked[members[k] * words + w] ^ want) & ~tie));
                }
            }
            ties += truth.tie_count;
            total += uint64_t(members.size()) * sets.count();
        }
        reference_json = {{"mismatched_bits", mismatched}, {"total_bits", total}, {"ties", ties}};
        reference_ms = msSince(t0);
    }

    t0 = std::chrono::steady_clock::now();
    const double lit_sum = shadeAndWrite(args, merged, light_pos, hits, visible);
    const double shade_ms = msSince(t0);
    const double total_ms = msSince(t_start);
    const penumbra::PenumbraCastingStats& st = result.stats;
    if (args.json) {
        Json j = reportHead(args, "hpc");
        j["width"] = args.width;
        j["height"] = args.height;
        j["triangles"] = oracle.triangleCount();
        j["view_samples"] = receivers.size();
        j["light_samples"] = sets.count();
        j["sets"] = sets.sets();
        j["light"] = {{"position", vec3Json(light_pos)}, {"radius", light_radius}};
        j["mean_visible_fraction"] = receivers.empty() ? 0.0 : lit_sum / double(receivers.size());
        j["hpc"] = {{"triangles_streamed", st.triangles},
                    {"triangles_degenerate", st.triangles_degenerate},
                    {"pairs_certified", st.pairs_certified},
                    {"pairs_classified", st.pairs_classified},
                    {"coplanar_skips", st.coplanar_skips},
                    {"nodes_visited", st.nodes_visited},
                    {"umbra_skips", st.umbra_skips},
                    {"mask_bytes_peak", st.mask_bytes_peak},
                    {"mask_bytes_full", st.mask_bytes_full}};
        if (args.reference) j["reference"] = reference_json;
        j["timings_ms"] = {{"load", load_ms},           {"view_samples", primary_ms}, {"penumbra_casting", casting_ms},
                           {"reference", reference_ms}, {"shade_and_write", shade_ms}, {"total", total_ms}};
        j["out"] = args.out;
        if (args.compare_shading) j["shading_compare"] = shadingComparePath(args.out);
        printReport(j);
    } else {
        std::printf("%s: %zu triangles, %zu view samples x %u light samples (%u sets), penumbra casting %.1f ms -> %s\n",
                    args.scene.c_str(), oracle.triangleCount(), receivers.size(), sets.count(), sets.sets(), casting_ms,
                    args.out.c_str());
        if (args.reference)
            std::printf("reference: %s of %s bits differ from the oracle (%s ties)\n", reference_json["mismatched_bits"].dump().c_str(),
                        reference_json["total_bits"].dump().c_str(), reference_json["ties"].dump().c_str());
    }
    return checksVerdict("hpc", 0, args.reference ? reference_json["mismatched_bits"].get<uint64_t>() : 0, "shadow bits");
}

int runReference(const Args& args, const penumbra::scene::Scene& scene, const penumbra::reference::VisibilityOracle& oracle,
                 const MergedScene& merged, const glm::dvec3& light_pos, double light_radius, double load_ms,
                 std::chrono::steady_clock::time_point t_start) {
    const std::vector<glm::dvec3> light_samples =
        penumbra::reference::sphereLightSamples(light_pos, light_radius, args.samples, 1);

    // ---- view samples: one primary ray per pixel ----
    auto t0 = std::chrono::steady_clock::now();
    const uint32_t w = args.width, h = args.height;
    const PrimaryHits hits = primaryHits(args, scene, oracle, merged);
    const std::vector<glm::dvec3>& receivers = hits.receivers;
    const std::vector<int64_t>& pixel_sample = hits.pixel_sample;
    const double primary_ms = msSince(t0);

    // ---- visibility: the exact oracle, every (view sample, light sample) pair ----
    t0 = std::chrono::steady_clock::now();
    std::vector<double> visible(receivers.size());
    uint64_t ties = 0;
    Json temporal;
    if (args.frames == 1) {
        const penumbra::reference::VisibilityResult visibility =
            evaluateWithProgress(oracle, receivers, light_samples, {}, "oracle visibility");
        for (size_t r = 0; r < receivers.size(); ++r) visible[r] = visibility.visibleFraction(r);
        ties = visibility.tie_count;
    } else {
        // Temporal accumulation (sintorn2008 §4.2, Fig. 7): frame f draws fresh K = 8 light-sample
        // sets (seed f) and every pixel uses set lightSampleSet(x, y, f, 8), so neighbours differ
        // and the running average converges; RMSE against an oracle image with many samples.
        const std::vector<glm::dvec3> reference_samples =
            penumbra::reference::sphereLightSamples(light_pos, light_radius, args.frames_reference, 7);
        const penumbra::reference::VisibilityResult truth =
            evaluateWithProgress(oracle, receivers, reference_samples, {}, "reference image");
        std::vector<double> sum(receivers.size(), 0.0);
        std::vector<uint32_t> pixel_of(receivers.size());
        for (size_t i = 0; i < pixel_sample.size(); ++i)
            if (pixel_sample[i] >= 0) pixel_of[static_cast<size_t>(pixel_sample[i])] = static_cast<uint32_t>(i);
        penumbra::Light light;
        light.center = light_pos;
        light.size = glm::dvec3(light_radius);
        const uint32_t sets = 8;
        Json rmse = Json::array();
        for (uint32_t f = 0; f < args.frames; ++f) {
            penumbra::LightSampleOptions sample_options;
            sample_options.count = args.samples;
            sample_options.sets = sets;
            sample_options.seed = 1000 + f;
            const penumbra::LightSampleSets frame_sets = penumbra::makeLightSampleSets(light, sample_options);
            for (uint32_t set = 0; set < sets; ++set) {
                std::vector<size_t> members;
                std::vector<glm::dvec3> points;
                for (size_t r = 0; r < receivers.size(); ++r) {
                    const uint32_t pixel = pixel_of[r];
                    if (penumbra::lightSampleSet(pixel % w, pixel / w, f, sets) != set) continue;
                    members.push_back(r);
                    points.push_back(receivers[r]);
                }
                if (members.empty()) continue;
                const std::vector<glm::dvec3> samples(frame_sets.worldSet(set), frame_sets.worldSet(set) + args.samples);
                const penumbra::reference::VisibilityResult part = oracle.evaluate(points, samples);
                for (size_t k = 0; k < members.size(); ++k) sum[members[k]] += part.visibleFraction(k);
                ties += part.tie_count;
            }
            double squares = 0;
            for (size_t r = 0; r < receivers.size(); ++r) {
                const double e = sum[r] / (f + 1) - truth.visibleFraction(r);
                squares += e * e;
            }
            const double value = receivers.empty() ? 0.0 : std::sqrt(squares / double(receivers.size()));
            rmse.push_back(value);
            std::fprintf(stderr, "soft_shadows: frame %u/%u: visibility RMSE %.5f vs %u-sample oracle (x sqrt(frames) = %.4f)\n",
                         f + 1, args.frames, value, args.frames_reference, value * std::sqrt(double(f + 1)));
        }
        for (size_t r = 0; r < receivers.size(); ++r) visible[r] = sum[r] / args.frames;
        temporal = {{"frames", args.frames},          {"sets", sets},
                    {"samples_per_frame", args.samples}, {"reference_samples", args.frames_reference},
                    {"rmse", rmse}};
    }
    const double visibility_ms = msSince(t0);

    // ---- shade: direct light (bent or Phong) with the sampled visibility, sRGB out ----
    t0 = std::chrono::steady_clock::now();
    const double lit_sum = shadeAndWrite(args, merged, light_pos, hits, visible);
    const double shade_ms = msSince(t0);

    const double total_ms = msSince(t_start);
    if (args.json) {
        Json j = reportHead(args, "reference");
        j["width"] = w;
        j["height"] = h;
        j["triangles"] = oracle.triangleCount();
        j["view_samples"] = receivers.size();
        j["light_samples"] = light_samples.size();
        j["light"] = {{"position", vec3Json(light_pos)}, {"radius", light_radius}};
        j["mean_visible_fraction"] = receivers.empty() ? 0.0 : lit_sum / double(receivers.size());
        j["reference"] = {{"ties", ties},
                          {"pairs", uint64_t(receivers.size()) * light_samples.size() * args.frames}};
        if (args.frames > 1) j["temporal"] = temporal;
        j["timings_ms"] = {{"load", load_ms},
                           {"view_samples", primary_ms},
                           {"visibility", visibility_ms},
                           {"shade_and_write", shade_ms},
                           {"total", total_ms}};
        j["out"] = args.out;
        if (args.compare_shading) j["shading_compare"] = shadingComparePath(args.out);
        printReport(j);
    } else {
        std::printf("%s: %zu triangles, %zu view samples x %zu light samples, %.1f ms -> %s\n", args.scene.c_str(),
                    oracle.triangleCount(), receivers.size(), light_samples.size(), total_ms, args.out.c_str());
    }
    return 0;
}

// =============================================================================================
// --mode dsm: deep shadow maps (lokovic2000) of semi-transparent casters

/// The casters of --mode dsm: every mesh of the scene but the ground, merged, in float (what a GPU
/// build gets). Every mesh receives; the ground only receives (it lies below everything it could
/// shadow). Triangle i is the i-th non-ground triangle in scene order.
struct DsmCasters {
    std::vector<glm::vec3> positions;
    std::vector<uint32_t> indices;
    std::vector<std::string> meshes;
    size_t triangles() const { return indices.size() / 3; }
};

DsmCasters dsmCasters(const penumbra::scene::Scene& scene) {
    penumbra::scene::Mesh merged = scene.casters();
    DsmCasters c{std::move(merged.positions), std::move(merged.indices), {}};
    for (const auto& mesh : scene.meshes)
        if (mesh.name != "ground") c.meshes.push_back(mesh.name);
    return c;
}

/// The light of --mode dsm: the scene's light as a point light with a perspective view from its
/// centre toward the centre of the casters' bounds (the scene's bounds without the ground: the
/// ground receives only, and a frustum around it would spend texels where nothing casts). The
/// field of view is fitted to the casters' bounding sphere (centre of their box, radius the
/// farthest vertex): a square frustum whose half-angle is asin(radius / distance) of the sphere
/// grown by 0.5% (so no caster's projection touches the map's border), i.e. the inscribed circle of
/// the map is the sphere's silhouette. Near and far are distance -/+ radius (with 1% margins); the
/// rasterization uses only clip x, y, w and the light depth, so they document the frustum rather
/// than clip anything.
struct DsmLightFit {
    penumbra::DsmLight light;
    glm::dvec3 centre{0.0};     ///< of the casters' bounding sphere (the view's target)
    double radius = 0.0;        ///< of the casters' bounding sphere
    double distance = 0.0;      ///< light centre to sphere centre
    double half_angle = 0.0;    ///< radians, vertical = horizontal
    double near = 0.0, far = 0.0;
    double texel_slope = 0.0;   ///< world size of a level-0 texel per unit of light depth: 2 tan(half_angle) / R
};

/// Refuses (exit 2) a light inside the casters' bounding sphere or so close that the sphere fills
/// more than 160 degrees of its view: no perspective frustum holds the casters then.
DsmLightFit fitDsmLight(const DsmCasters& casters, const glm::dvec3& light_pos, uint32_t resolution) {
    DsmLightFit fit;
    glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
    for (const glm::vec3& p : casters.positions) {
        lo = glm::min(lo, glm::dvec3(p));
        hi = glm::max(hi, glm::dvec3(p));
    }
    if (casters.positions.empty()) {  // nothing casts: any frustum below the light (every lookup is 1)
        lo = hi = light_pos - glm::dvec3(0.0, 1.0, 0.0);
    }
    fit.centre = 0.5 * (lo + hi);
    for (const glm::vec3& p : casters.positions) fit.radius = std::max(fit.radius, glm::length(glm::dvec3(p) - fit.centre));
    fit.radius = std::max(fit.radius * 1.005, 1e-6 * std::max(1.0, glm::length(fit.centre)));
    fit.distance = glm::length(fit.centre - light_pos);
    const double kMaxHalfAngle = glm::radians(80.0);
    if (!(fit.distance > fit.radius) || std::asin(fit.radius / fit.distance) > kMaxHalfAngle) {
        std::ostringstream out;
        out.precision(9);
        out << "--mode dsm: the light at " << vec3Text(light_pos) << " is " << fit.distance
            << " from the centre of the casters' bounding sphere " << vec3Text(fit.centre) << " (radius " << fit.radius
            << "): a deep shadow map needs every caster in front of the light, within 80 degrees of its axis; with --light-pos, "
               "move it farther than "
            << fit.radius / std::sin(kMaxHalfAngle) << " from that centre";
        usageError(out.str());
    }
    fit.half_angle = std::asin(fit.radius / fit.distance);
    fit.near = 0.99 * (fit.distance - fit.radius);
    fit.far = 1.01 * (fit.distance + fit.radius);
    const glm::dvec3 axis = (fit.centre - light_pos) / fit.distance;
    const glm::dvec3 up = std::fabs(axis.y) < 0.99 ? glm::dvec3(0.0, 1.0, 0.0) : glm::dvec3(0.0, 0.0, 1.0);
    fit.light.view = glm::mat4(glm::lookAt(light_pos, fit.centre, up));
    fit.light.projection = glm::mat4(glm::perspective(2.0 * fit.half_angle, 1.0, fit.near, fit.far));
    fit.texel_slope = 2.0 * std::tan(fit.half_angle) / double(resolution);
    return fit;
}

/// Depth bias of a DSM lookup (lokovic2000 leaves it to the renderer, as for shadow maps). A
/// receiver lying on a caster triangle must not be shadowed by that triangle's own fragments at the
/// sub-samples the bilinear lookup averages: the 2 x 2 texels around it, whose sub-samples lie ~1
/// texel (up to ~2.1) away laterally, where the triangle's light depth differs from the receiver's
/// by (lateral distance) x tan(theta), theta = angle between the triangle's normal and the direction
/// to the light. The lookup depth is depth - bias with
///   bias = texel(depth) x (kDsmBiasTexels + kDsmBiasSlopeTexels x min(tan theta, kDsmBiasMaxSlope)),
/// texel(depth) = depth x DsmLightFit::texel_slope, the world size of a texel at that depth: the
/// slope term covers the receiver's own triangle (and its neighbours of the same surface), the
/// constant term float rounding of depths and curved surfaces. Measured at R = 256, S = 16,
/// opacity 0.5, 256 x 192 pixels, on receivers lying on casters that the oracle sees fully lit:
/// without a bias the torus knot's mean self-shadowing 1 - V is 0.25 (columns 0.25); with these
/// constants 0.003 (columns 0.004). A slope factor of 2.2 halves that residue but lets light leak
/// past casters just in front of a receiver (mean V - T over shadowed receivers +60%, RMSE +25%).
/// Beyond the clamp (within ~7 degrees of edge-on to the light) some self-shadowing remains.
constexpr double kDsmBiasTexels = 0.5;
constexpr double kDsmBiasSlopeTexels = 1.0;
constexpr double kDsmBiasMaxSlope = 8.0;

/// The deep shadow map and what its build reports.
struct DeepShadowMapBuild {
    penumbra::DsmMapCpu map;
    uint64_t fragments = 0;        ///< caster fragments over every sub-sample list
    double rasterize_ms = 0.0;     ///< CPU: fragments (rasterization + sort); GPU: the whole build (glFinish)
    double merge_ms = 0.0;         ///< per-texel merge + compression (the GPU's merge and compress)
    const char* executor = "cpu";  ///< which build made it
};

/// The ONE place the deep shadow map is built: the GPU executor (penumbra/gl/deep_shadow_map.hpp)
/// on a headless context, its offsets and vertices read back into a DsmMapCpu, or the CPU twin
/// (buildDsmFragmentsCpu + buildDsmMapCpu: the same vertices on llvmpipe). The rest of --mode dsm
/// sees only the map, its counters and phase times. The GPU build's capacities are fixed when the
/// builder is made (engine-style); a tool does not know the fragment count in advance, so it
/// starts from an estimate and rebuilds once with the counts the status block reports.
DeepShadowMapBuild buildDeepShadowMap(const penumbra::DsmSetup& setup, const penumbra::DsmLight& light,
                                      const DsmCasters& casters, const penumbra::DsmOpacity& opacity, bool gpu) {
    DeepShadowMapBuild build;
    auto t0 = std::chrono::steady_clock::now();
    if (gpu) {
        build.executor = "gpu";
        penumbra::gl::HeadlessContext context;
        penumbra::gl::Buffer positions = penumbra::gl::Buffer::fromVector(casters.positions);
        penumbra::gl::Buffer indices = penumbra::gl::Buffer::fromVector(casters.indices);
        penumbra::gl::DsmCasterBuffers buffers;
        buffers.positions = {positions.id(), 0, positions.size()};
        buffers.indices = {indices.id(), 0, indices.size()};
        buffers.index_count = static_cast<uint32_t>(casters.indices.size());
        penumbra::gl::DsmCapacity capacity;
        const uint64_t sub_samples = uint64_t(setup.resolution) * setup.resolution * setup.samples;
        capacity.fragments = std::max<uint64_t>(1u << 20, std::min<uint64_t>(sub_samples, 0xFFFFFFF0ull));
        capacity.vertices = std::max<uint64_t>(1u << 20, uint64_t(setup.resolution) * setup.resolution * 4);
        for (int attempt = 0; attempt < 3; ++attempt) {
            std::fprintf(stderr,
                         "soft_shadows: deep shadow map (GPU): %zu caster triangles into %u^2 texels x %u sub-samples "
                         "(capacity %llu fragments, %llu vertices)...\n",
                         casters.triangles(), setup.resolution, setup.samples,
                         static_cast<unsigned long long>(capacity.fragments), static_cast<unsigned long long>(capacity.vertices));
            penumbra::gl::DeepShadowMapBuilder builder(setup, capacity);
            t0 = std::chrono::steady_clock::now();
            builder.build(light, opacity, buffers);
            glFinish();
            build.rasterize_ms = msSince(t0);  // the whole GPU build (llvmpipe: no per-stage timers here)
            const penumbra::gl::DsmStatus status = builder.readStatus();
            build.fragments = status.fragments;
            if (status.fragment_overflow > 0) {
                capacity.fragments = uint64_t(status.fragments) + 16;
                continue;
            }
            build.map = builder.readMap();
            uint64_t vertices = 0;
            for (uint32_t l = 0; l < build.map.levels; ++l) vertices += build.map.vertexCount(l);
            if (status.vertex_overflow > 0) {
                capacity.vertices = vertices + 16;
                continue;
            }
            return build;
        }
        std::fprintf(stderr, "soft_shadows: the GPU deep shadow map still overflowed after resizing\n");
        std::exit(1);
    }
    std::fprintf(stderr, "soft_shadows: deep shadow map (CPU): rasterizing %zu caster triangles into %u^2 texels x %u sub-samples...\n",
                 casters.triangles(), setup.resolution, setup.samples);
    penumbra::DsmFragmentsCpu fragments =
        penumbra::buildDsmFragmentsCpu(setup, light, casters.positions, casters.indices, opacity);
    build.fragments = fragments.fragments.size();
    build.rasterize_ms = msSince(t0);
    t0 = std::chrono::steady_clock::now();
    std::fprintf(stderr, "soft_shadows: deep shadow map (CPU): merging and compressing %llu fragments (%.0f s so far)...\n",
                 static_cast<unsigned long long>(build.fragments), build.rasterize_ms / 1000.0);
    build.map = penumbra::buildDsmMapCpu(setup, fragments);
    build.merge_ms = msSince(t0);
    return build;
}

// --mode dsm: primary hits, the deep shadow map of the casters, a biased bilinear lookup per
// receiver times the direct light; --reference: the exact transmittance per receiver.
int runDsm(const Args& args, const penumbra::scene::Scene& scene, const penumbra::reference::VisibilityOracle& oracle,
           const MergedScene& merged, const glm::dvec3& light_pos, double load_ms,
           std::chrono::steady_clock::time_point t_start) {
    // ---- setup: casters, light, options (before any long work: a bad light is exit 2) ----
    auto t0 = std::chrono::steady_clock::now();
    const DsmCasters casters = dsmCasters(scene);
    const DsmLightFit fit = fitDsmLight(casters, light_pos, args.dsm_res);
    const penumbra::DsmSetup setup = penumbra::deepShadowMapSetup(dsmOptions(args));
    penumbra::DsmOpacity opacity;
    opacity.mesh = glm::vec3(static_cast<float>(args.opacity));
    const penumbra::DsmParams params = penumbra::deepShadowMapParams(setup, fit.light, opacity);
    const double setup_ms = msSince(t0);

    // ---- view samples: one primary ray per pixel ----
    t0 = std::chrono::steady_clock::now();
    const PrimaryHits hits = primaryHits(args, scene, oracle, merged);
    const std::vector<glm::dvec3>& receivers = hits.receivers;
    const double primary_ms = msSince(t0);

    // ---- the map ----
    const DeepShadowMapBuild build = buildDeepShadowMap(setup, fit.light, casters, opacity, args.dsm_build == "gpu");
    const penumbra::DsmMapCpu& map = build.map;

    // ---- lookups: bilinear at level 0, at the receiver's light depth minus the bias ----
    t0 = std::chrono::steady_clock::now();
    std::vector<double> visible(receivers.size(), 1.0);
    std::vector<uint8_t> outside(receivers.size(), 0);
    parallelFor(0, receivers.size(), [&](size_t r) {
        const glm::dvec3& p = receivers[r];
        const penumbra::DsmCoord coord = penumbra::dsmCoord(params, glm::vec3(p));
        if (!coord.inside) {  // no caster projects outside the map's inscribed circle: fully lit
            outside[r] = 1;
            return;
        }
        const uint32_t* t = &merged.indices[size_t(hits.hit_triangle[hits.receiver_pixel[r]]) * 3];
        const glm::dvec3 face = glm::cross(merged.positions[t[1]] - merged.positions[t[0]],
                                           merged.positions[t[2]] - merged.positions[t[0]]);
        const double face_length = glm::length(face);
        const double cos_theta = face_length > 0.0 ? std::fabs(glm::dot(face / face_length, glm::normalize(light_pos - p))) : 0.0;
        const double tan_theta = cos_theta > 0.0 ? std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta)) / cos_theta
                                                 : kDsmBiasMaxSlope;
        const double texel = double(coord.depth) * fit.texel_slope;
        const double bias = texel * (kDsmBiasTexels + kDsmBiasSlopeTexels * std::min(tan_theta, kDsmBiasMaxSlope));
        visible[r] = penumbra::dsmLookup(map, coord.u, coord.v, static_cast<float>(double(coord.depth) - bias), 0.0f);
    });
    const double lookup_ms = msSince(t0);
    const size_t outside_count = size_t(std::count(outside.begin(), outside.end(), uint8_t(1)));

    // ---- --reference: the exact transmittance of the open segment (receiver, light centre) over the
    // same casters and opacity; ties (a fragile crossing: the exact value is uncertain by a factor
    // 1 - opacity) are counted and left out of the error ----
    Json reference_json;
    double reference_ms = 0.0;
    if (args.reference) {
        t0 = std::chrono::steady_clock::now();
        const penumbra::reference::TransmittanceOracle transmittance(casters.positions, casters.indices, args.opacity);
        std::vector<penumbra::reference::TransmittanceSegment> segments(receivers.size());
        for (size_t r = 0; r < receivers.size(); ++r) segments[r] = {receivers[r], light_pos};
        std::vector<double> exact(receivers.size(), 1.0);
        std::vector<uint8_t> tie(receivers.size(), 0);
        {
            Progress progress("oracle transmittance", receivers.size());
            std::vector<penumbra::reference::TransmittanceSegment> part;
            inChunks(receivers.size(), 4096, progress, [&](size_t begin, size_t end) {
                part.assign(segments.begin() + static_cast<std::ptrdiff_t>(begin), segments.begin() + static_cast<std::ptrdiff_t>(end));
                const auto batch = transmittance.evaluate(part);
                for (size_t k = 0; k < batch.results.size(); ++k) {
                    exact[begin + k] = batch.results[k].transmittance;
                    tie[begin + k] = batch.results[k].tie;
                }
            });
        }
        uint64_t compared = 0, ties = 0, above_tolerance = 0, compared_inside = 0;
        double squares = 0.0, max_error = 0.0, signed_sum = 0.0, dsm_sum = 0.0, exact_sum = 0.0, squares_inside = 0.0;
        for (size_t r = 0; r < receivers.size(); ++r) {
            if (tie[r]) {
                ++ties;
                continue;
            }
            const double e = visible[r] - exact[r];
            squares += e * e;
            signed_sum += e;
            max_error = std::max(max_error, std::fabs(e));
            above_tolerance += std::fabs(e) > double(setup.tolerance);
            dsm_sum += visible[r];
            exact_sum += exact[r];
            ++compared;
            if (!outside[r]) {
                squares_inside += e * e;
                ++compared_inside;
            }
        }
        const double n = compared ? double(compared) : 1.0;
        reference_json = {{"rmse", compared ? std::sqrt(squares / n) : 0.0},
                          {"max_error", max_error},
                          {"mean_error", signed_sum / n},
                          {"receivers", receivers.size()},
                          {"compared", compared},
                          {"ties", ties},
                          {"above_tolerance", above_tolerance},
                          // Receivers outside the map are lit on both sides (no caster projects there).
                          {"compared_inside_map", compared_inside},
                          {"rmse_inside_map", compared_inside ? std::sqrt(squares_inside / double(compared_inside)) : 0.0},
                          {"dsm_mean_transmittance", dsm_sum / n},
                          {"oracle_mean_transmittance", exact_sum / n},
                          {"target", "exact transmittance of the open segment (receiver, light centre); ties left out"}};
        reference_ms = msSince(t0);
    }

    // ---- shade: direct light (bent or Phong) times the transmittance, sRGB out ----
    t0 = std::chrono::steady_clock::now();
    const double lit_sum = shadeAndWrite(args, merged, light_pos, hits, visible);
    const double shade_ms = msSince(t0);
    const double total_ms = msSince(t_start);
    const uint64_t vertices = map.vertexCount(0);
    const uint64_t depth_map_bytes = uint64_t(setup.resolution) * setup.resolution * setup.samples * 4;
    if (args.json) {
        Json j = reportHead(args, "dsm");
        j["width"] = args.width;
        j["height"] = args.height;
        j["triangles"] = oracle.triangleCount();
        j["view_samples"] = receivers.size();
        j["light"] = {{"position", vec3Json(light_pos)},
                      {"kind", "point"},
                      {"target", vec3Json(fit.centre)},
                      {"fov_degrees", glm::degrees(2.0 * fit.half_angle)},
                      {"near", fit.near},
                      {"far", fit.far}};
        j["casters"] = {{"meshes", casters.meshes},
                        {"triangles", casters.triangles()},
                        {"opacity", args.opacity},
                        {"bounding_sphere", {{"centre", vec3Json(fit.centre)}, {"radius", fit.radius}}}};
        j["mean_visible_fraction"] = receivers.empty() ? 0.0 : lit_sum / double(receivers.size());
        j["dsm"] = {{"executor", build.executor},
                    {"resolution", setup.resolution},
                    {"samples", setup.samples},
                    {"tolerance", setup.tolerance},
                    {"opacity", args.opacity},
                    {"filter", "box"},
                    {"filter_radius", setup.options.filter_radius},
                    {"levels", setup.levels},
                    {"lookup", "bilinear, level 0"},
                    {"fragments", build.fragments},
                    {"vertices", vertices},
                    {"vertices_per_texel", double(vertices) / (double(setup.resolution) * setup.resolution)},
                    {"bytes", map.bytes()},
                    {"depth_map_bytes", depth_map_bytes},
                    {"depth_bias", {{"texels", kDsmBiasTexels}, {"slope_texels", kDsmBiasSlopeTexels}, {"max_slope", kDsmBiasMaxSlope}}},
                    {"receivers_outside_map", outside_count},
                    {"build_ms", {{"setup", setup_ms},
                                  {"rasterize", build.rasterize_ms},
                                  {"merge_compress", build.merge_ms},
                                  {"total", build.rasterize_ms + build.merge_ms}}}};
        if (args.reference) j["reference"] = reference_json;
        j["timings_ms"] = {{"load", load_ms},
                           {"view_samples", primary_ms},
                           {"dsm_build", build.rasterize_ms + build.merge_ms},
                           {"lookup", lookup_ms},
                           {"reference", reference_ms},
                           {"shade_and_write", shade_ms},
                           {"total", total_ms}};
        j["out"] = args.out;
        if (args.compare_shading) j["shading_compare"] = shadingComparePath(args.out);
        printReport(j);
    } else {
        std::printf("%s (dsm %u^2 x %u, opacity %g): %zu caster triangles, %llu fragments, %llu vertices (%.2f MiB), build "
                    "%.1f ms, %zu view samples -> %s\n",
                    args.scene.c_str(), setup.resolution, setup.samples, args.opacity, casters.triangles(),
                    static_cast<unsigned long long>(build.fragments), static_cast<unsigned long long>(vertices),
                    double(map.bytes()) / double(1 << 20), build.rasterize_ms + build.merge_ms, receivers.size(),
                    args.out.c_str());
        if (args.reference)
            std::printf("reference: transmittance RMSE %.4g, max error %.4g over %s receivers (%s ties left out)\n",
                        reference_json["rmse"].get<double>(), reference_json["max_error"].get<double>(),
                        reference_json["compared"].dump().c_str(), reference_json["ties"].dump().c_str());
    }
    return 0;
}

/// Volumetric mode (billeter2010): light shafts of a spot light at the scene's light in a homogeneous
/// medium (--fog). The spot frames the casters and the ground around them (1.5x the casters' box);
/// its R x R shadow map (--sm-res) is rasterized on the GPU, tessellated into the closed light
/// volume (penumbra/gl/light_volume.hpp: adaptive or static), and the volume is drawn over the
/// camera's depth (the exact primary hits) so its airlight is added to the directly lit image.
/// --reference: per pixel the converged ray march of the same shadow map (nearest texel, 512 steps;
/// JSON reference.rmse) and, on every 4th pixel each way, the ray march with exact visibility (the
/// oracle, 256 steps; reference.rmse_oracle). Writes <out> and <out>_airlight.png (the airlight).
int runVolumetric(const Args& args, const penumbra::scene::Scene& scene, const penumbra::reference::VisibilityOracle& oracle,
                  const MergedScene& merged, const glm::dvec3& light_pos, double load_ms,
                  std::chrono::steady_clock::time_point t_start) {
    const uint32_t w = args.width, h = args.height, r = args.sm_res;
    // ---- the spot light (a bad one is exit 2, before any long work) ----
    penumbra::scene::Bounds box;
    for (size_t m = scene.meshes.size() > 1 && args.ground ? 1 : 0; m < scene.meshes.size(); ++m) box.extend(scene.meshes[m].bounds());
    const glm::vec3 centre = box.center(), half = 0.75f * (box.max - box.min);
    glm::mat4 light_vp_f;
    try {
        light_vp_f = penumbra::lightViewProjectionForBounds(glm::vec4(glm::vec3(light_pos), 1.0f), centre - half, centre + half);
    } catch (const penumbra::Error& e) {
        usageError("--mode volumetric: the spot light at the scene's light cannot frame the casters: ", e.what());
    }
    const glm::dmat4 light_vp(light_vp_f);
    penumbra::AirlightMedium medium;
    medium.sigma_s = args.fog_sigma_s;
    medium.sigma_t = args.fog_sigma_t;
    // Intensity: unit irradiance at the casters' centre without the medium.
    const double intensity = glm::dot(glm::dvec3(centre) - light_pos, glm::dvec3(centre) - light_pos);
    const penumbra::AirlightSetup airlight = penumbra::airlightSetup(medium, intensity);
    penumbra::LightVolumeOptions volume_options;
    volume_options.tessellation = args.tessellation == "static" ? penumbra::LightVolumeTessellation::Static
                                                                : penumbra::LightVolumeTessellation::Adaptive;
    volume_options.flatness = 1e-6;
    const penumbra::LightVolumeSetup volume_setup = penumbra::lightVolumeSetup(r, volume_options);

    // ---- the camera's exact primary hits: the scene's distance per pixel ----
    auto t0 = std::chrono::steady_clock::now();
    const PrimaryHits hits = primaryHits(args, scene, oracle, merged);
    const double primary_ms = msSince(t0);
    const glm::dvec3 eye(scene.camera.eye);
    const glm::dmat4 camera = glm::dmat4(scene.camera.projection(float(w) / float(h))) * glm::dmat4(scene.camera.view());
    const size_t pixels = size_t(w) * h;
    // GPU textures are bottom-up: texel (x, y) is image pixel (x, h - 1 - y).
    const auto imageIndex = [&](size_t texel) { return (h - 1 - texel / w) * size_t(w) + texel % w; };
    std::vector<float> window(pixels, 1.0f);
    std::vector<double> distance(pixels, penumbra::kAirlightMaxDistance);
    std::vector<glm::dvec3> dirs(pixels);
    const glm::dmat4 inverse_camera = glm::inverse(camera);
    for (size_t texel = 0; texel < pixels; ++texel) {
        const size_t i = imageIndex(texel);
        const glm::dvec4 far_point = inverse_camera * glm::dvec4(2.0 * (texel % w + 0.5) / w - 1.0, 2.0 * (texel / w + 0.5) / h - 1.0, 1.0, 1.0);
        dirs[texel] = glm::normalize(glm::dvec3(far_point) / far_point.w - eye);
        if (hits.pixel_sample[i] < 0) continue;
        const glm::dvec4 clip = camera * glm::dvec4(hits.hit_point[i], 1.0);
        window[texel] = float(0.5 * clip.z / clip.w + 0.5);
        // The distance the GPU reconstructs from that float depth (what the references clamp to).
        const glm::dvec4 p = inverse_camera * glm::dvec4(2.0 * (texel % w + 0.5) / w - 1.0, 2.0 * (texel / w + 0.5) / h - 1.0,
                                                       2.0 * double(window[texel]) - 1.0, 1.0);
        distance[texel] = glm::length(glm::dvec3(p) / p.w - eye);
    }

    // ---- GPU: shadow map, light volume, render ----
    penumbra::gl::HeadlessContext context;
    t0 = std::chrono::steady_clock::now();
    const penumbra::scene::GpuScene gpu_scene(scene);
    penumbra::scene::GBuffer shadow_map(r, r);
    shadow_map.render(gpu_scene, light_vp_f);
    std::vector<float> depth(size_t(r) * r);
    glGetTextureImage(shadow_map.depthTexture(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(4 * depth.size()), depth.data());
    const double shadow_map_ms = msSince(t0);
    penumbra::gl::LightVolumeTessellator tessellator(volume_setup);
    tessellator.enableStageTimers(true);
    tessellator.tessellate(shadow_map.depthTexture());
    const penumbra::gl::LightVolumeStageTimes stages = tessellator.stageTimes();
    const penumbra::LightVolumeMesh mesh = tessellator.readMesh();
    penumbra::gl::Texture camera_depth(GL_TEXTURE_2D), lit(GL_TEXTURE_2D), shafts(GL_TEXTURE_2D);
    glTextureStorage2D(camera_depth.id(), 1, GL_DEPTH_COMPONENT32F, GLsizei(w), GLsizei(h));
    glTextureSubImage2D(camera_depth.id(), 0, 0, 0, GLsizei(w), GLsizei(h), GL_DEPTH_COMPONENT, GL_FLOAT, window.data());
    // The directly lit image: albedo x (ambient + N.L x exact visibility of the light's centre).
    std::vector<glm::vec4> base(pixels, glm::vec4(0.08f, 0.09f, 0.12f, 1.0f));
    parallelFor(0, pixels, [&](size_t texel) {
        const size_t i = imageIndex(texel);
        if (hits.pixel_sample[i] < 0) return;
        const glm::dvec3 p = hits.hit_point[i], to_light = light_pos - p;
        const double lambert = std::max(0.0, glm::dot(hits.hit_normal[i], glm::normalize(to_light)));
        glm::dvec3 tmp;
        const bool lit_here = penumbra::reference::shadowMapProject({light_vp, r, nullptr, nullptr}, p, tmp) &&
                              !oracle.closestHit(p, to_light, 1e-6, 1.0 - 1e-9).hit;
        const glm::dvec3 albedo = merged.material[hits.hit_triangle[i]] ? glm::dvec3(0.85, 0.45, 0.2) : glm::dvec3(0.75, 0.75, 0.72);
        base[texel] = glm::vec4(glm::vec3(albedo * (0.12 + 0.88 * lambert * (lit_here ? 1.0 : 0.0))), 1.0f);
    });
    const std::vector<glm::vec4> zeros(pixels, glm::vec4(0.0f));
    glTextureStorage2D(lit.id(), 1, GL_RGBA32F, GLsizei(w), GLsizei(h));
    glTextureSubImage2D(lit.id(), 0, 0, 0, GLsizei(w), GLsizei(h), GL_RGBA, GL_FLOAT, base.data());
    glTextureStorage2D(shafts.id(), 1, GL_RGBA32F, GLsizei(w), GLsizei(h));
    glTextureSubImage2D(shafts.id(), 0, 0, 0, GLsizei(w), GLsizei(h), GL_RGBA, GL_FLOAT, zeros.data());
    penumbra::gl::LightVolumeRenderer renderer(w, h, airlight);
    penumbra::gl::LightVolumeView view;
    view.camera_view_projection = camera;
    view.eye = eye;
    view.light_view_projection = light_vp;
    view.light_position = light_pos;
    renderer.render(tessellator, view, camera_depth.id(), shafts.id());  // the airlight alone
    glFinish();
    t0 = std::chrono::steady_clock::now();
    renderer.render(tessellator, view, camera_depth.id(), lit.id());
    glFinish();
    const double render_ms = msSince(t0);
    std::vector<glm::vec4> out(pixels), air(pixels);
    glGetTextureImage(lit.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(16 * pixels), out.data());
    glGetTextureImage(shafts.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(16 * pixels), air.data());

    // ---- --reference: ray marches ----
    Json reference_json;
    double reference_ms = 0.0;
    if (args.reference) {
        t0 = std::chrono::steady_clock::now();
        penumbra::reference::ShadowMapView map_view;
        map_view.view_projection = light_vp;
        map_view.resolution = r;
        map_view.depth = &depth;
        std::vector<double> march(pixels, 0.0);
        std::vector<std::pair<double, double>> interval(pixels);  // each ray's stretch inside the spot's frustum
        for (size_t texel = 0; texel < pixels; ++texel)
            interval[texel] = penumbra::reference::frustumInterval(map_view, eye, dirs[texel], std::min(distance[texel], 1e6));
        {
            Progress progress("ray march (shadow map, 512 steps)", pixels);
            inChunks(pixels, w, progress, [&](size_t begin, size_t end) {
                parallelFor(begin, end, [&](size_t texel) {
                    march[texel] = penumbra::reference::rayMarchExact(
                        eye, dirs[texel], interval[texel].first, interval[texel].second, 512,
                        [&](const glm::dvec3& x) { return penumbra::reference::shadowMapLit(map_view, penumbra::reference::ShadowMapLookup::Nearest, x); },
                        [&](double t) { return penumbra::airlight<double>(airlight, eye, dirs[texel], light_pos, t); });
                });
            });
        }
        std::vector<size_t> sparse;
        for (size_t texel = 0; texel < pixels; ++texel)
            if ((texel % w) % 4 == 0 && (texel / w) % 4 == 0) sparse.push_back(texel);
        std::vector<double> exact(sparse.size(), 0.0);
        {
            Progress progress("ray march (exact visibility, 256 steps)", sparse.size());
            inChunks(sparse.size(), 256, progress, [&](size_t begin, size_t end) {
                parallelFor(begin, end, [&](size_t k) {
                    const size_t texel = sparse[k];
                    exact[k] = penumbra::reference::rayMarchExact(
                        eye, dirs[texel], interval[texel].first, interval[texel].second, 256,
                        [&](const glm::dvec3& x) { return penumbra::reference::oracleLit(map_view, oracle, light_pos, x); },
                        [&](double t) { return penumbra::airlight<double>(airlight, eye, dirs[texel], light_pos, t); });
                });
            });
        }
        double squares = 0.0, peak = 0.0, squares_oracle = 0.0, squares_march_oracle = 0.0, max_error = 0.0;
        for (size_t texel = 0; texel < pixels; ++texel) {
            const double e = double(air[texel].r) - march[texel];
            squares += e * e;
            max_error = std::max(max_error, std::fabs(e));
            peak = std::max(peak, march[texel]);
        }
        for (size_t k = 0; k < sparse.size(); ++k) {
            const double e = double(air[sparse[k]].r) - exact[k], m = march[sparse[k]] - exact[k];
            squares_oracle += e * e;
            squares_march_oracle += m * m;
        }
        reference_json = {{"rmse", std::sqrt(squares / double(pixels))},
                          {"max_error", max_error},
                          {"rmse_oracle", std::sqrt(squares_oracle / double(sparse.size()))},
                          {"ray_march_rmse_oracle", std::sqrt(squares_march_oracle / double(sparse.size()))},
                          {"peak_airlight", peak},
                          {"target", "rmse: the ray march of the same shadow map (nearest texel, 512 steps over the ray's stretch in the spot's frustum, each lit step's airlight exact) on every pixel; "
                                     "rmse_oracle: the ray march with exact visibility (256 steps) on every 4th pixel each way"},
                          {"oracle_pixels", sparse.size()}};
        reference_ms = msSince(t0);
    }

    // ---- images ----
    penumbra::scene::ImageRgb8 image = penumbra::scene::makeImageRgb8(w, h), shafts_image = penumbra::scene::makeImageRgb8(w, h);
    double air_peak = 0.0;
    for (const glm::vec4& a : air) air_peak = std::max(air_peak, double(a.r));
    for (size_t texel = 0; texel < pixels; ++texel) {
        const size_t i = imageIndex(texel);
        for (int k = 0; k < 3; ++k) {
            image.pixels[3 * i + k] = penumbra::scene::linearToSrgb8(out[texel][k]);
            shafts_image.pixels[3 * i + k] = penumbra::scene::linearToSrgb8(air_peak > 0 ? float(air[texel].r / air_peak) : 0.0f);
        }
    }
    penumbra::scene::writePng(args.out, image);
    const std::string shafts_path = siblingPath(args.out, "_airlight");
    penumbra::scene::writePng(shafts_path, shafts_image);
    const double total_ms = msSince(t_start);
    if (args.json) {
        Json j = reportHead(args, "volumetric");
        j["width"] = w;
        j["height"] = h;
        j["triangles"] = oracle.triangleCount();
        j["fog"] = {{"sigma_s", args.fog_sigma_s}, {"sigma_t", args.fog_sigma_t}, {"phase", "isotropic"}, {"intensity", intensity}};
        j["light_volume"] = {{"shadow_map", r},
                             {"tessellation", args.tessellation},
                             {"flatness", volume_options.flatness},
                             {"triangles", mesh.triangleCount()},
                             {"floor_triangles", mesh.floor_triangles},
                             {"static_triangles", volume_setup.maxTriangles()},
                             {"triangles_vs_static", double(mesh.triangleCount()) / double(2.0 * r * r + 4.0 * r)},
                             {"edge_map_ms", stages.edge_map},
                             {"tessellate_ms", stages.tessellate},
                             {"render_ms", render_ms},
                             {"peak_airlight", air_peak}};
        if (args.reference) j["reference"] = reference_json;
        j["timings_ms"] = {{"load", load_ms},      {"view_samples", primary_ms}, {"shadow_map", shadow_map_ms},
                           {"reference", reference_ms}, {"total", total_ms}};
        j["out"] = args.out;
        j["airlight_out"] = shafts_path;
        printReport(j);
    } else {
        std::printf("%s (volumetric, %u^2 shadow map, %s): %llu volume triangles (%.1f %% of static), render %.1f ms -> %s, %s\n",
                    args.scene.c_str(), r, args.tessellation.c_str(), static_cast<unsigned long long>(mesh.triangleCount()),
                    100.0 * double(mesh.triangleCount()) / double(2.0 * r * r + 4.0 * r), render_ms, args.out.c_str(),
                    shafts_path.c_str());
        if (args.reference)
            std::printf("reference: airlight RMSE %.4g against the shadow-map ray march, %.4g against exact visibility (peak %.4g)\n",
                        reference_json["rmse"].get<double>(), reference_json["rmse_oracle"].get<double>(),
                        reference_json["peak_airlight"].get<double>());
    }
    return 0;
}

/// --origin: the world is the scene translated by `origin` (double). What the renderers and the
/// oracle see is camera-relative — world minus the camera's world position, subtracted in double
/// and rounded once to float (penumbra::relativePosition) — so float precision does not depend on
/// how far from the world origin the scene is. `light_pos` (the scene's frame) moves along.
//
// The range it supports: |origin| (each axis) up to kOriginRange = 2^26 times the scene's extent
// (its box diagonal). The two double roundings (of world = p + origin and of the camera's world
// position) then move a point by at most 2^-52 * 2^26 * extent = extent / 2^26 before the float
// rounding, an eighth of a float ulp at the scene's extent (2^-23 relative): the renderers see
// the untranslated scene's floats to within one float rounding, and the GPU and the oracle see
// the very same floats. Beyond it the doubles shred the geometry (at 1e15 for a unit scene, a
// point moves by 0.06), so the run is refused.
constexpr double kOriginRange = 67108864.0;  // 2^26

void applyOrigin(penumbra::scene::Scene& scene, const glm::dvec3& origin, glm::dvec3& light_pos) {
    if (origin == glm::dvec3(0.0)) return;
    {
        const auto [lo, hi] = sceneBounds(scene);
        const double extent = lo.x <= hi.x ? glm::length(hi - lo) : 0.0;
        const double reach = std::max({std::fabs(origin.x), std::fabs(origin.y), std::fabs(origin.z)});
        if (!(reach <= kOriginRange * extent)) {
            std::ostringstream out;
            out.precision(9);
            out << "--origin " << vec3Text(origin) << " is beyond the range this scene supports: |x|, |y|, |z| <= 2^26 x "
                << "the scene's extent " << extent << " = " << kOriginRange * extent
                << " (farther, the double roundings of world positions move points by more than 1/8 of a float ulp "
                   "of the scene's size)";
            usageError(out.str());
        }
    }
    const glm::dvec3 frame = glm::dvec3(scene.camera.eye) + origin;
    auto relative = [&](const glm::vec3& p) { return penumbra::relativePosition(glm::dvec3(p) + origin, frame); };
    for (auto& mesh : scene.meshes) {
        for (auto& p : mesh.positions) p = relative(p);
    }
    scene.camera.eye = relative(scene.camera.eye);
    scene.camera.target = relative(scene.camera.target);
    scene.light.position = relative(scene.light.position);
    light_pos = (light_pos + origin) - frame;
}

penumbra::scene::Scene loadSceneUnchecked(const Args& args) {
    penumbra::scene::Scene scene;
    if (args.scene.rfind("builtin:", 0) == 0) {
        scene = penumbra::scene::load(args.scene);
        if (!args.ground) {
            scene.meshes.erase(std::remove_if(scene.meshes.begin(), scene.meshes.end(),
                                              [](const penumbra::scene::Mesh& m) { return m.name == "ground"; }),
                               scene.meshes.end());
        }
    } else {
        penumbra::scene::ObjOptions options;
        options.ground = args.ground;
        Progress progress("loading the OBJ", 1000);
        options.progress = [&](double f) {
            progress.update(static_cast<size_t>(f * 1000.0));
            return true;
        };
        penumbra::scene::ObjReport report;
        scene = penumbra::scene::loadObj(args.scene, options, report);
        for (const std::string& w : report.warnings) std::fprintf(stderr, "soft_shadows: warning: %s\n", w.c_str());
    }
    return scene;
}

/// --scene: a scene that cannot be loaded (no such file, a parse error, an unknown built-in) is
/// bad input: exit 2 with the loader's message, which names the file and line.
penumbra::scene::Scene loadScene(const Args& args) {
    try {
        return loadSceneUnchecked(args);
    } catch (const UsageError&) {
        throw;
    } catch (const std::bad_alloc&) {
        throw;
    } catch (const std::exception& e) {
        usageError("--scene '", args.scene, "' cannot be loaded: ", e.what());
    }
}

}  // namespace

int main(int argc, char** argv) {
    Args args;
    RawArgs raw;
    CLI::App app{"soft_shadows: renders a scene lit by a spherical light with penumbra and writes a PNG "
                 "(and, with --json, a one-line JSON report on stdout).",
                 "soft_shadows"};
    app.footer("Modes:\n"
               "  reference  every pixel's visibility of --samples light samples (a spherical light) from the exact\n"
               "             double-precision oracle on the CPU: soft shadows\n"
               "  soft       the GPU sample-based soft-shadow pipeline (lists, influence regions, light-sample LUT);\n"
               "             --reference compares every bit with the oracle and writes <out>_reference.png, <out>_error.png\n"
               "  hard       the GPU alias-free hard-shadow pipeline from the light's centre on a headless GL context\n"
               "             (PENUMBRA_GL=egl|osmesa); --reference adds the oracle's verdict on the same samples\n"
               "  hpc        hierarchical penumbra casting on the CPU (laine2005; --sets K sets of --samples per pixel,\n"
               "             8 by default); --reference compares every bit with the oracle on the same light samples\n"
               "  dsm        a deep shadow map (lokovic2000, CPU build) of semi-transparent casters: every mesh but the\n"
               "             ground casts with --opacity A (0.5); a point light at the scene's light, frustum fitted to\n"
               "             the casters' bounding sphere; --dsm-res R (256) x R texels, --dsm-samples S (16) per texel,\n"
               "             --tolerance E (0 = 1/(2S)); bilinear lookup with a depth bias; --reference: RMSE and max\n"
               "             error against the exact transmittance to the light (JSON reference.rmse, max_error)\n"
               "  volumetric light shafts in fog (billeter2010): the spot light's --sm-res R (1024) shadow map tessellated\n"
               "             into a light volume on the GPU (--tessellation adaptive|static), drawn with the airlight of\n"
               "             --fog SIGMA_S,SIGMA_T (0.05,0.08); --reference: RMSE against ray marching the shadow map\n"
               "             (reference.rmse) and with exact visibility (reference.rmse_oracle); writes <out>_airlight.png\n"
               "Built-in scenes: torus_knot columns hairball grass. Progress of long phases goes to stderr.\n"
               "Exit codes: 0 done, 1 failed while running or a check asked for (--check-skips, an exact mode's --reference)\n"
               "found a difference, 2 bad arguments or a run that cannot work.");
    addOptions(app, args, raw);
    // "--flag=" with nothing after '=': CLI11 would then blame the next argument; name the flag.
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg.size() > 3 && arg.compare(0, 2, "--") == 0 && arg.back() == '=') {
            std::fprintf(stderr, "soft_shadows: %s is empty (give a value after '=')\n(soft_shadows --help lists the options)\n",
                         arg.substr(0, arg.size() - 1).c_str());
            return 2;
        }
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);  // --help: prints the help, 0
        return code == 0 ? 0 : 2;
    }
    const auto t_start = std::chrono::steady_clock::now();
    try {
        checkArgs(app, args, raw);
        checkMemory(args, 0);  // sizes that cannot run whatever the scene: before loading it

        // ---- scene ----
        auto t0 = std::chrono::steady_clock::now();
        penumbra::scene::Scene scene = loadScene(args);
        glm::dvec3 light_pos = args.has_light_pos ? args.light_pos : glm::dvec3(scene.light.position);
        applyOrigin(scene, args.origin, light_pos);
        const double light_radius = args.light_radius > 0 ? args.light_radius : double(scene.light.radius);
        if (args.mode != "hard" && args.mode != "dsm" && args.mode != "volumetric")
            checkLight(scene, light_pos, light_radius);  // those three: a point light
        checkMemory(args, scene.triangleCount());

        const MergedScene merged = merge(scene);
        const penumbra::reference::VisibilityOracle oracle(merged.positions, merged.indices);
        const double load_ms = msSince(t0);
        if (args.mode == "hard") return runHard(args, scene, oracle, merged, light_pos, load_ms, t_start);
        if (args.mode == "soft") return runSoft(args, scene, oracle, merged, light_pos, light_radius, load_ms, t_start);
        if (args.mode == "hpc") return runHpc(args, scene, oracle, merged, light_pos, light_radius, load_ms, t_start);
        if (args.mode == "dsm") return runDsm(args, scene, oracle, merged, light_pos, load_ms, t_start);
        if (args.mode == "volumetric") return runVolumetric(args, scene, oracle, merged, light_pos, load_ms, t_start);
        return runReference(args, scene, oracle, merged, light_pos, light_radius, load_ms, t_start);
    } catch (const UsageError& e) {
        std::fprintf(stderr, "soft_shadows: %s\n(soft_shadows --help lists the options)\n", e.what.c_str());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "soft_shadows: %s\n", e.what());
        return 1;
    }
}
