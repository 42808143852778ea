// penumbra — conservative rasterization with a geometry-shader emitter (sintorn2008 §3.2, Fig. 4;
// the exact variant after Hasselgren, Akenine-Möller & Ohlsson, GPU Gems 2 ch. 42 [HAMO05]).
//
// Integration summary
//   needs:    GL 4.5 (geometry shaders, fp64 in the rare clipping path); the viewport you render
//             into; the driver's GL_SUBPIXEL_BITS (GL guarantees >= 4; llvmpipe and desktop GPUs 8).
//   produces: conservativeRasterSetup() -> the PenumbraConservativeParams block the emitter reads and
//             the #define permutation for the chosen options (pure C++, no GL);
//             GLSL snippet penumbra/conservative_raster/conservative_raster.glsl with
//               int penumbraConservativeEmit(vec4 clip0, vec4 clip1, vec4 clip2, params)
//             and the hook PENUMBRA_CONSERVATIVE_EMIT_VERTEX(position, box) you define (write
//             gl_Position and your flat outputs, EmitVertex()); fragment snippet
//             conservative_raster_clip.glsl with penumbraConservativeInsideBox(gl_FragCoord.xy, box);
//             ready entries conservative_raster.{vert,geom,frag}.glsl to copy;
//             the Fixed-6 two-pass plan ConservativeRasterSetup::spill (below), with the spill
//             predicate penumbraConservativeNeedsSpill / conservativeNeedsSpill() and the snippet
//             conservative_raster_spill.glsl; GL helpers that record it in
//             penumbra/gl/conservative_raster.hpp;
//             CPU twins: conservativeHull() (the same emitted polygon, float, same operations),
//             rasterizeConservativeHull() (GL's pixel-centre rule on it: the GPU's fragments),
//             and the ground truth: conservativeReferencePolygon() + polygonTouchesPixel() (an exact
//             separating-axis test in double) -> conservativeRequiredPixels().
//
// Coverage contract. Let T be the input triangle (the float clip coordinates the geometry stage
// receives, taken as exact) clipped to the near plane dot(near_plane, clip) >= 0 and to
// w >= min_w, projected to viewport-relative pixels. Every viewport pixel (i, j), 0 <= i < width,
// 0 <= j < height, whose CLOSED square [i, i+1] x [j, j+1] intersects T receives at least one
// fragment. Touching counts: a vertex on a pixel corner covers the 4 pixels around it, an edge on
// a pixel boundary the pixels on both sides, and a zero-area T (collinear or coincident points)
// covers every pixel its segment or point touches — unless drop_degenerate is set, in which case
// triangles thinner than the thin threshold (height 2*area/diameter <= tau0 + tau_rel * diameter
// pixels with tau0 = 2^-10, tau_rel = 2^-18; all zero-area triangles included) are dropped. The far plane is not clipped. NaN or Inf
// in any clip coordinate drops the triangle (no fragments). Valid when the driver snaps to at least
// `subpixel_bits` bits and rounds float operations within GLSL's precision rules.
//
// What is emitted (always counter-clockwise in window space, whatever the input winding; cull
// back faces yourself before calling the emitter if you need to):
//   * an unclipped triangle (all vertices inside the near plane and the guard band): Fixed6 emits
//     the seed's 6 vertices / 4 triangles (a case-iii corner over-covers by at most one pixel);
//     Exact emits the exact dilation (at most 7 vertices);
//   * Fixed6 programs: the direct pass (PENUMBRA_CONSERVATIVE_DIRECT=1) declares max_vertices = 6
//     (sintorn2008 §3.2; declared GS output size sets GS throughput on real GPUs) and emits every
//     unclipped triangle; each triangle that needs clipping (conservativeNeedsSpill: it crosses the
//     near plane, w = min_w or the guard band and is not entirely outside one of them) is appended
//     to a spill buffer (ConservativeSpillPlan: capacity fixed at setup, overflow counted) and a
//     second program draws that buffer with one glDrawArraysIndirect whose command is the spill
//     header itself. Together the two passes emit exactly the single pass's hulls. Exact keeps one
//     pass at max_vertices 13 (its unclipped hull alone needs 7); the single pass (`defines`,
//     13) also stays available for geometry stages without a spill hook;
//   * a triangle crossing the near plane or the guard band (G pixels around the viewport): it is
//     clipped in double precision in clip space and the resulting n-gon (n <= 9) is emitted as its
//     exact dilation (n + 4 <= 13 vertices) in both variants — the fixed-6 trick is for triangles;
//   * a thin triangle or polygon: the segment between its farthest points dilated by h plus its
//     thickness (6 vertices, a square of 4 for a point);
//   * gl_Position.z: the triangle's NDC depth plane at each hull vertex clamped to depth_clip_range
//     (so GL never clips a hull vertex in z; inside the triangle the interpolated depth is the plane
//     unless clamping happened); thin: the nearest vertex depth. w = 1 everywhere: use flat outputs.
//   * several viewports or layers: one params block per viewport; set gl_ViewportIndex / gl_Layer in
//     your hook.
#ifndef PENUMBRA_CONSERVATIVE_RASTER_HPP
#define PENUMBRA_CONSERVATIVE_RASTER_HPP

#include "penumbra/detail/float_ops.hpp"
#include "penumbra/detail/shared.hpp"
#include "penumbra/error.hpp"
#include "penumbra/shader_defines.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace penumbra::shared {
// The constants and the parameter block, once for C++ and GLSL (STYLE habit 2). Found on the
// include path when shaders/ is on it, else next to this header in the source tree.
#if defined(__has_include) && __has_include(<penumbra/conservative_raster/conservative_raster_shared.h>)
#include <penumbra/conservative_raster/conservative_raster_shared.h>
#else
#include "../../shaders/penumbra/conservative_raster/conservative_raster_shared.h"
#endif
}  // namespace penumbra::shared

namespace penumbra {

/// The std140 parameter block the emitter reads (conservative_raster_shared.h).
using ConservativeRasterParams = shared::PenumbraConservativeParams;
static_assert(sizeof(ConservativeRasterParams) == 80, "std140 layout the shaders assume: five vec4");
static_assert(PENUMBRA_CONSERVATIVE_MAX_VERTICES == PENUMBRA_CONSERVATIVE_MAX_POLYGON + 4,
              "the exact dilation of an n-gon has n + 4 vertices");
static_assert(PENUMBRA_CONSERVATIVE_FIXED6_MAX_VERTICES == 6, "sintorn2008 §3.2: six vertices per triangle");
using ConservativeSpillHeader = shared::PenumbraConservativeSpillHeader;
using ConservativeSpillTriangle = shared::PenumbraConservativeSpillTriangle;
static_assert(sizeof(ConservativeSpillHeader) == 32 && offsetof(ConservativeSpillHeader, capacity) == 16 &&
                  offsetof(ConservativeSpillHeader, overflow) == 20,
              "std430 layout the shaders assume; the first 16 bytes are a DrawArraysIndirectCommand");
static_assert(sizeof(ConservativeSpillTriangle) == 64 && offsetof(ConservativeSpillTriangle, payload) == 48,
              "std430 layout the shaders assume: three vec4 and a uvec4");

/// Largest viewport side the margins are derived for (GL_MAX_VIEWPORT_DIMS is 16384..32768).
inline constexpr int kConservativeMaxViewport = 32768;
inline constexpr int kConservativeMaxVertices = PENUMBRA_CONSERVATIVE_MAX_VERTICES;
inline constexpr int kConservativeMaxPolygon = PENUMBRA_CONSERVATIVE_MAX_POLYGON;
/// What the Fixed-6 direct pass's geometry stage declares (sintorn2008 §3.2).
inline constexpr int kConservativeFixed6MaxVertices = PENUMBRA_CONSERVATIVE_FIXED6_MAX_VERTICES;
/// Largest spill capacity the setup accepts (triangles; 64 bytes each, 1 GiB), and the capacity
/// it picks when neither spill_capacity nor max_triangles is given.
inline constexpr uint32_t kConservativeMaxSpillCapacity = 1u << 24;
inline constexpr uint32_t kConservativeDefaultSpillCapacity = 1u << 16;
/// Float error allowance per pixel of coordinate range (16 ulps: the divide, viewport transform and
/// hull arithmetic each round, GLSL's division is allowed 2.5 ulps).
inline constexpr float kConservativeFloatSlack = 1.0f / 1048576.0f;  // 2^-20
/// Thin threshold: height <= kConservativeThinAbsolute + kConservativeThinRelative * diameter
/// pixels. The relative term is 64 ulps: above it the float orientation test cannot be wrong.
inline constexpr float kConservativeThinAbsolute = 1.0f / 1024.0f;
inline constexpr float kConservativeThinRelative = 1.0f / 262144.0f;  // 2^-18

enum class ConservativeVariant : int {
    Fixed6 = 0,  ///< sintorn2008 §3.2: always 6 vertices / 4 triangles per unclipped triangle
    Exact = 1,   ///< GPU Gems 2 ch. 42: the exact hull, at most 7 vertices per unclipped triangle
};

inline const char* conservativeVariantName(ConservativeVariant variant) {
    return variant == ConservativeVariant::Exact ? "exact" : "fixed6";
}

/// Value-initialised = defaults, except the viewport size, which must be given.
struct ConservativeRasterOptions {
    int viewport_x = 0;       ///< glViewport x (window pixels)
    int viewport_y = 0;       ///< glViewport y
    int viewport_width = 0;   ///< 1 .. kConservativeMaxViewport
    int viewport_height = 0;  ///< 1 .. kConservativeMaxViewport
    ConservativeVariant variant = ConservativeVariant::Fixed6;
    bool drop_degenerate = false;  ///< drop triangles at or below the thin threshold (zero area included)
    bool clip_to_box = false;      ///< fragment stage discards outside the pixel-expanded bounding box
    int subpixel_bits = 4;         ///< the driver's GL_SUBPIXEL_BITS (1..16); 4 = GL's minimum, safe anywhere
    float extra_margin = 0.0f;     ///< pixels added to the computed margin (>= 0)
    float guard_band = 0.0f;       ///< G in pixels (>= 1); 0 = max(width, height). Larger G keeps more
                                   ///< triangles on the unclipped fast path, smaller G a smaller margin
    glm::vec4 near_plane{0.0f, 0.0f, 1.0f, 1.0f};  ///< kept: dot(near_plane, clip) >= 0; GL's z >= -w.
                                                    ///< glClipControl(.., GL_ZERO_TO_ONE): (0, 0, 1, 0);
                                                    ///< reversed Z with ZERO_TO_ONE: (0, 0, -1, 1)
    float min_w = 1e-6f;  ///< also kept: w >= min_w (> 0), so nothing at or behind the eye is divided
    glm::vec2 depth_clip_range{-1.0f, 1.0f};  ///< NDC z range GL clips to; (0, 1) under
                                              ///< glClipControl(.., GL_ZERO_TO_ONE). Emitted z is clamped to it
    /// Fixed6 two-pass plan: the most triangles one direct draw submits (0 = not given). Sizes the
    /// spill buffer so that it can never overflow, whatever the view.
    uint32_t max_triangles = 0;
    /// Fixed6 two-pass plan: triangles the spill buffer holds (0 = max_triangles, or
    /// kConservativeDefaultSpillCapacity when that is 0 too). Smaller than max_triangles saves
    /// memory when few triangles need clipping; an overflow loses triangles and is counted in
    /// the header (ConservativeSpillHeader::overflow).
    uint32_t spill_capacity = 0;
};

/// The Fixed-6 two-pass plan (pure data, no GL; an engine records it with its own RHI):
///   0. before each direct draw, write `reset` (32 bytes) at the start of the spill range;
///      bind the range (`buffer_bytes` long) as SSBO PENUMBRA_CONSERVATIVE_SPILL_BINDING;
///   1. direct pass: your triangles through a geometry stage built with `direct_defines`
///      (penumbra/conservative_raster/conservative_raster.geom.glsl or your own with
///      PENUMBRA_CONSERVATIVE_DIRECT=1), max_vertices = `direct_max_vertices` (6);
///   2. glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
///   3. spill pass: a program built with `spill_defines` (max_vertices = `spill_max_vertices`,
///      13), any vertex array (no attributes are read), GL_DRAW_INDIRECT_BUFFER = the spill buffer,
///      glDrawArraysIndirect(GL_TRIANGLES, spill offset + `indirect_offset`).
/// The triangles spilled = header.count / 3 + header.overflow (read back only if you want it);
/// exactly those for which conservativeNeedsSpill() is true.
/// Exact variant: `enabled` is false, one pass with `ConservativeRasterSetup::defines` (13).
struct ConservativeSpillPlan {
    bool enabled = false;
    uint32_t capacity = 0;           ///< spilled triangles the buffer holds
    uint64_t header_bytes = sizeof(ConservativeSpillHeader);      ///< 32
    uint64_t triangle_bytes = sizeof(ConservativeSpillTriangle);  ///< 64
    uint64_t triangles_offset = sizeof(ConservativeSpillHeader);  ///< array start (bytes into the range)
    uint64_t indirect_offset = 0;    ///< DrawArraysIndirectCommand (bytes into the range)
    uint64_t buffer_bytes = 0;       ///< header + capacity triangles
    ConservativeSpillHeader reset{};  ///< {0, 1, 0, 0, capacity, 0, 0, 0}
    ShaderDefines direct_defines;     ///< defines + PENUMBRA_CONSERVATIVE_DIRECT=1
    ShaderDefines spill_defines;      ///< defines + PENUMBRA_CONSERVATIVE_SPILL_DRAW=1
    int direct_max_vertices = kConservativeFixed6MaxVertices;
    int spill_max_vertices = kConservativeMaxVertices;
};

/// What conservativeRasterSetup derived; pass `params` to the shaders (std140 block) and `defines`
/// to gl::buildProgram / assembleShader for the geometry and fragment entries or your own.
/// `defines` alone builds the single-pass emitter (every triangle, max_vertices 13: what a geometry
/// stage that calls penumbraConservativeEmit without a spill hook declares); Fixed6 draws at 6
/// output vertices through the two-pass plan `spill`.
struct ConservativeRasterSetup {
    ConservativeRasterParams params{};
    ShaderDefines defines;
    ConservativeRasterOptions options;
    float margin = 0.0f;      ///< pixels beyond the half-pixel dilation
    float half_size = 0.0f;   ///< h = 0.5 + margin
    float guard_band = 0.0f;  ///< G in pixels
    /// The single-pass geometry stage's max_vertices (13 for both variants: clipped polygons).
    int max_vertices = kConservativeMaxVertices;
    ConservativeSpillPlan spill;  ///< Fixed6: the two-pass plan (direct pass at 6); Exact: disabled

    int width() const { return options.viewport_width; }
    int height() const { return options.viewport_height; }
    /// The emitter's thin threshold for a polygon of the given diameter (pixels).
    float thinThreshold(float diameter) const { return params.expansion.z + params.expansion.w * diameter; }
};

/// Pure setup: validates the options and derives the margins. margin = 2^-subpixel_bits (GL snaps
/// each vertex by at most half a subpixel, an edge moves by at most sqrt(2)/2 of one) +
/// 2^-20 * (max(width, height) + G) (float rounding at the largest coordinate the hull arithmetic
/// sees) + extra_margin. Throws penumbra::Error naming the first bad value.
inline ConservativeRasterSetup conservativeRasterSetup(const ConservativeRasterOptions& options) {
    const auto& o = options;
    PENUMBRA_CHECK(o.viewport_width >= 1 && o.viewport_width <= kConservativeMaxViewport,
                   "penumbra: conservativeRasterSetup: viewport_width = ", o.viewport_width, " must be in [1, ",
                   kConservativeMaxViewport, "]");
    PENUMBRA_CHECK(o.viewport_height >= 1 && o.viewport_height <= kConservativeMaxViewport,
                   "penumbra: conservativeRasterSetup: viewport_height = ", o.viewport_height, " must be in [1, ",
                   kConservativeMaxViewport, "]");
    PENUMBRA_CHECK(std::abs(o.viewport_x) <= kConservativeMaxViewport && std::abs(o.viewport_y) <= kConservativeMaxViewport,
                   "penumbra: conservativeRasterSetup: viewport origin (", o.viewport_x, ", ", o.viewport_y,
                   ") must lie within +-", kConservativeMaxViewport);
    PENUMBRA_CHECK(o.subpixel_bits >= 1 && o.subpixel_bits <= 16, "penumbra: conservativeRasterSetup: subpixel_bits = ",
                   o.subpixel_bits, " must be in [1, 16] (query GL_SUBPIXEL_BITS)");
    PENUMBRA_CHECK(std::isfinite(o.extra_margin) && o.extra_margin >= 0.0f && o.extra_margin <= 16.0f,
                   "penumbra: conservativeRasterSetup: extra_margin = ", o.extra_margin, " must be in [0, 16] pixels");
    PENUMBRA_CHECK(std::isfinite(o.guard_band) && (o.guard_band == 0.0f || (o.guard_band >= 1.0f &&
                   o.guard_band <= static_cast<float>(kConservativeMaxViewport))),
                   "penumbra: conservativeRasterSetup: guard_band = ", o.guard_band, " must be 0 (default) or in [1, ",
                   kConservativeMaxViewport, "] pixels");
    PENUMBRA_CHECK(std::isfinite(o.near_plane.x) && std::isfinite(o.near_plane.y) && std::isfinite(o.near_plane.z) &&
                   std::isfinite(o.near_plane.w) && (o.near_plane.z != 0.0f || o.near_plane.w != 0.0f),
                   "penumbra: conservativeRasterSetup: near_plane = (", o.near_plane.x, ", ", o.near_plane.y, ", ",
                   o.near_plane.z, ", ", o.near_plane.w, ") must be finite with a z or w term");
    PENUMBRA_CHECK(std::isfinite(o.min_w) && o.min_w > 0.0f, "penumbra: conservativeRasterSetup: min_w = ", o.min_w,
                   " must be a positive finite number");
    PENUMBRA_CHECK(std::isfinite(o.depth_clip_range.x) && std::isfinite(o.depth_clip_range.y) &&
                   o.depth_clip_range.x >= -1.0f && o.depth_clip_range.x < o.depth_clip_range.y &&
                   o.depth_clip_range.y <= 1.0f,
                   "penumbra: conservativeRasterSetup: depth_clip_range = (", o.depth_clip_range.x, ", ",
                   o.depth_clip_range.y, ") must satisfy -1 <= min < max <= 1");
    PENUMBRA_CHECK(static_cast<int>(o.variant) == 0 || static_cast<int>(o.variant) == 1,
                   "penumbra: conservativeRasterSetup: variant = ", static_cast<int>(o.variant), " is not a ConservativeVariant");
    PENUMBRA_CHECK(o.spill_capacity <= kConservativeMaxSpillCapacity, "penumbra: conservativeRasterSetup: spill_capacity = ",
                   o.spill_capacity, " must be at most ", kConservativeMaxSpillCapacity, " triangles");
    PENUMBRA_CHECK(o.spill_capacity != 0 || o.max_triangles <= kConservativeMaxSpillCapacity,
                   "penumbra: conservativeRasterSetup: max_triangles = ", o.max_triangles,
                   " would size a spill buffer above ", kConservativeMaxSpillCapacity,
                   " triangles; give a smaller spill_capacity");

    ConservativeRasterSetup s;
    s.options = o;
    const float w = static_cast<float>(o.viewport_width), h = static_cast<float>(o.viewport_height);
    s.guard_band = o.guard_band == 0.0f ? std::max(w, h) : o.guard_band;
    const float range = std::max(w, h) + s.guard_band;
    s.margin = std::ldexp(1.0f, -o.subpixel_bits) + kConservativeFloatSlack * range + o.extra_margin;
    s.half_size = 0.5f + s.margin;
    s.params.viewport = glm::vec4(static_cast<float>(o.viewport_x), static_cast<float>(o.viewport_y), w, h);
    s.params.near_plane = o.near_plane;
    s.params.expansion = glm::vec4(s.half_size, s.margin, kConservativeThinAbsolute, kConservativeThinRelative);
    s.params.clipping = glm::vec4(s.guard_band, 1.0f + 2.0f * s.guard_band / w, 1.0f + 2.0f * s.guard_band / h, o.min_w);
    s.params.depth = glm::vec4(o.depth_clip_range, 0.0f, 0.0f);
    s.defines = {{"PENUMBRA_CONSERVATIVE_EXACT", o.variant == ConservativeVariant::Exact ? "1" : "0"},
                 {"PENUMBRA_CONSERVATIVE_DROP_DEGENERATE", o.drop_degenerate ? "1" : "0"},
                 {"PENUMBRA_CONSERVATIVE_CLIP_TO_BOX", o.clip_to_box ? "1" : "0"}};
    if (o.variant == ConservativeVariant::Fixed6) {
        ConservativeSpillPlan& plan = s.spill;
        plan.enabled = true;
        plan.capacity = o.spill_capacity != 0 ? o.spill_capacity
                        : o.max_triangles != 0 ? o.max_triangles
                                               : kConservativeDefaultSpillCapacity;
        plan.buffer_bytes = plan.triangles_offset + static_cast<uint64_t>(plan.capacity) * plan.triangle_bytes;
        plan.reset = ConservativeSpillHeader{0u, 1u, 0u, 0u, plan.capacity, 0u, 0u, 0u};
        plan.direct_defines = s.defines;
        plan.direct_defines.push_back({"PENUMBRA_CONSERVATIVE_DIRECT", "1"});
        plan.spill_defines = s.defines;
        plan.spill_defines.push_back({"PENUMBRA_CONSERVATIVE_SPILL_DRAW", "1"});
    }
    return s;
}

/// How the emitter treated a triangle.
enum class ConservativeHullKind : int {
    Dropped = 0,  ///< NaN/Inf input, or thin with drop_degenerate
    Culled,       ///< nothing left after clipping, or entirely outside the viewport
    Triangle,     ///< unclipped triangle (Fixed6: 6 vertices, Exact: <= 7)
    Clipped,      ///< clipped polygon, exact dilation (<= 13)
    Thin,         ///< thin triangle/polygon: dilated segment or point
    Fallback,     ///< inconsistent extreme order (never expected): the pixel-expanded box
};

/// The CPU twin's result: exactly what the geometry stage emits for one triangle.
struct ConservativeHull {
    ConservativeHullKind kind = ConservativeHullKind::Dropped;
    int count = 0;                                          ///< emitted vertices (0 = none)
    std::array<glm::vec2, kConservativeMaxVertices> pixels{};     ///< hull, CCW, viewport-relative pixels
    std::array<glm::vec4, kConservativeMaxVertices> positions{};  ///< emitted gl_Position, strip order
    glm::vec4 box{};  ///< window-space (xmin, ymin, xmax, ymax) handed to the fragment stage
    /// kind == Triangle: the unclipped triangle in viewport-relative pixels, counter-clockwise, and
    /// the dilation h of the hull around it (conservativeInsideDilatedTriangle; the compute light
    /// passes' per-pixel test).
    std::array<glm::vec2, 3> triangle{};
    float dilation = 0.0f;
    /// Fixed6 two-pass plan: the direct pass spilled it (conservativeNeedsSpill) and the spill
    /// pass emitted this hull; false in the single pass (Exact) and for direct-pass hulls.
    bool spilled = false;
};

namespace detail {

inline bool conservativeFinite(const glm::vec4& v) {
    for (int i = 0; i < 4; ++i) {
        uint32_t bits;
        std::memcpy(&bits, &v[i], sizeof bits);
        if ((bits & 0x7f800000u) == 0x7f800000u) return false;
    }
    return true;
}

inline glm::vec2 conservativeCorner(int k) {
    return glm::vec2(k < 2 ? 1.0f : -1.0f, (k == 1 || k == 2) ? 1.0f : -1.0f);
}

inline int conservativeEdgeCorner(glm::vec2 d) {
    if (d.y > 0.0f && d.x >= 0.0f) return 0;
    if (d.x < 0.0f && d.y >= 0.0f) return 1;
    if (d.y < 0.0f && d.x <= 0.0f) return 2;
    return 3;
}

/// a * b rounded and kept opaque (detail/float_ops.hpp), so the compiler cannot contract it with a
/// following add into an FMA; the GLSL side uses `precise` for the same reason.
inline float conservativeMulRounded(float a, float b) { return mulRounded(a, b); }

inline float conservativeCross(glm::vec2 a, glm::vec2 b) {
    return conservativeMulRounded(a.x, b.y) - conservativeMulRounded(a.y, b.x);
}

// Mirrors penumbraConservativeNearDistance: left to right, every product rounded.
inline float conservativeNearDistance(const glm::vec4& p, const glm::vec4& c) {
    float d = conservativeMulRounded(p.x, c.x) + conservativeMulRounded(p.y, c.y);
    d = d + conservativeMulRounded(p.z, c.z);
    return d + conservativeMulRounded(p.w, c.w);
}

// Mirrors penumbraConservativeVertexInside.
inline bool conservativeVertexInside(const glm::vec4& c, const shared::PenumbraConservativeParams& p) {
    return conservativeNearDistance(p.near_plane, c) >= 0.0f && c.w >= p.clipping.w &&
           std::abs(c.x) <= p.clipping.y * c.w && std::abs(c.y) <= p.clipping.z * c.w;
}

inline double conservativeMulRounded(double a, double b) { return mulRounded(a, b); }

// Mirrors penumbraConservativePlane (left to right, every product rounded).
inline double conservativePlane(int i, const glm::dvec4& c, const shared::PenumbraConservativeParams& p) {
    if (i == 0) {
        const glm::dvec4 n(p.near_plane);
        double d = conservativeMulRounded(n.x, c.x) + conservativeMulRounded(n.y, c.y);
        d = d + conservativeMulRounded(n.z, c.z);
        return d + conservativeMulRounded(n.w, c.w);
    }
    if (i == 1) return c.w - static_cast<double>(p.clipping.w);
    const double g = static_cast<double>(i < 4 ? p.clipping.y : p.clipping.z);
    const double coordinate = i < 4 ? c.x : c.y;
    return ((i & 1) == 0 ? coordinate : -coordinate) + conservativeMulRounded(g, c.w);
}

// from + t * (to - from) per component, every product rounded (mirrors the clipper's precise lerp).
inline glm::dvec4 conservativeLerpFrom(const glm::dvec4& from, double t, const glm::dvec4& to) {
    glm::dvec4 r;
    for (int k = 0; k < 4; ++k) r[k] = from[k] + conservativeMulRounded(t, to[k] - from[k]);
    return r;
}

// x * x + y * y with both products rounded (mirrors the GLSL's precise squared lengths).
inline float conservativeLength2(glm::vec2 d) { return conservativeMulRounded(d.x, d.x) + conservativeMulRounded(d.y, d.y); }

// Mirrors penumbraConservativeOutsideOnePlane.
inline bool conservativeOutsideOnePlane(const glm::vec4 (&clip)[3], const shared::PenumbraConservativeParams& p) {
    const glm::dvec4 a(clip[0]), b(clip[1]), c(clip[2]);
    for (int plane = 0; plane < 6; ++plane) {
        if (conservativePlane(plane, a, p) < 0.0 && conservativePlane(plane, b, p) < 0.0 && conservativePlane(plane, c, p) < 0.0) {
            return true;
        }
    }
    return false;
}

// Mirrors penumbraConservativeClip: Sutherland-Hodgman in double, intersections from the kept end.
inline int conservativeClip(const glm::vec4 (&clip)[3], const shared::PenumbraConservativeParams& p,
                            glm::vec2* polygon, float* depth) {
    glm::dvec4 poly[kConservativeMaxPolygon], next[kConservativeMaxPolygon];
    for (int i = 0; i < 3; ++i) poly[i] = glm::dvec4(clip[i]);
    int n = 3;
    for (int plane = 0; plane < 6 && n > 0; ++plane) {
        int m = 0;
        glm::dvec4 prev = poly[n - 1];
        double d_prev = conservativePlane(plane, prev, p);
        for (int i = 0; i < n; ++i) {
            const glm::dvec4 cur = poly[i];
            const double d_cur = conservativePlane(plane, cur, p);
            if (d_cur >= 0.0) {
                if (d_prev < 0.0) next[m++] = conservativeLerpFrom(cur, d_cur / (d_cur - d_prev), prev);
                next[m++] = cur;
            } else if (d_prev >= 0.0) {
                next[m++] = conservativeLerpFrom(prev, d_prev / (d_prev - d_cur), cur);
            }
            prev = cur;
            d_prev = d_cur;
        }
        PENUMBRA_ASSERT(m <= kConservativeMaxPolygon);
        n = m;
        for (int i = 0; i < n; ++i) poly[i] = next[i];
    }
    const glm::dvec2 half_size = glm::dvec2(p.viewport.z, p.viewport.w) * 0.5;
    for (int i = 0; i < n; ++i) {
        polygon[i] = glm::vec2(static_cast<float>(conservativeMulRounded(poly[i].x / poly[i].w, half_size.x) + half_size.x),
                               static_cast<float>(conservativeMulRounded(poly[i].y / poly[i].w, half_size.y) + half_size.y));
        depth[i] = static_cast<float>(poly[i].z / poly[i].w);
    }
    return n;
}

inline int conservativeChainHull(const glm::vec2* polygon, int n, float h, glm::vec2* hull) {
    int extreme[4] = {0, 0, 0, 0};
    for (int i = 1; i < n; ++i) {
        const glm::vec2 q = polygon[i];
        const glm::vec2 b = polygon[extreme[0]], r = polygon[extreme[1]], t = polygon[extreme[2]], l = polygon[extreme[3]];
        if (q.y < b.y || (q.y == b.y && q.x > b.x)) extreme[0] = i;
        if (q.x > r.x || (q.x == r.x && q.y > r.y)) extreme[1] = i;
        if (q.y > t.y || (q.y == t.y && q.x < t.x)) extreme[2] = i;
        if (q.x < l.x || (q.x == l.x && q.y < l.y)) extreme[3] = i;
    }
    int turns = 0;
    for (int k = 0; k < 4; ++k) turns += (extreme[(k + 1) & 3] - extreme[k] + n) % n;
    if (turns != n && turns != 0) return -1;
    int count = 0;
    for (int k = 0; k < 4; ++k) {
        const int length = (extreme[(k + 1) & 3] - extreme[k] + n) % n + 1;
        const glm::vec2 corner = h * conservativeCorner(k);
        for (int j = 0; j < length; ++j) hull[count++] = polygon[(extreme[k] + j) % n] + corner;
    }
    return count;
}

inline int conservativeFixedHull(const glm::vec2* polygon, float h, glm::vec2* hull) {
    for (int i = 0; i < 3; ++i) {
        const glm::vec2 q = polygon[i];
        const glm::vec2 d_in = q - polygon[(i + 2) % 3];
        const glm::vec2 d_out = polygon[(i + 1) % 3] - q;
        const int k_in = conservativeEdgeCorner(d_in), k_out = conservativeEdgeCorner(d_out);
        const int steps = (k_out - k_in) & 3;
        if (steps == 3) return -1;
        glm::vec2 a = q + h * conservativeCorner(k_in);
        glm::vec2 b = q + h * conservativeCorner(k_out);
        if (steps == 2) {  // case iii: extend both edges by one pixel (2h) past the corner
            const glm::vec2 n_in = d_in / std::sqrt(conservativeLength2(d_in));
            const glm::vec2 n_out = d_out / std::sqrt(conservativeLength2(d_out));
            a = glm::vec2(a.x + conservativeMulRounded(2.0f * h, n_in.x), a.y + conservativeMulRounded(2.0f * h, n_in.y));
            b = glm::vec2(b.x - conservativeMulRounded(2.0f * h, n_out.x), b.y - conservativeMulRounded(2.0f * h, n_out.y));
        }
        hull[2 * i] = a;
        hull[2 * i + 1] = b;
    }
    return 6;
}

}  // namespace detail

/// CPU twin of penumbraConservativeEmit: the same polygon, in float with the same operations (the
/// clipping path in double, as on the GPU), for one triangle in clip space.
inline ConservativeHull conservativeHull(const glm::vec4& clip0, const glm::vec4& clip1, const glm::vec4& clip2,
                                         const ConservativeRasterSetup& setup) {
    using detail::conservativeCross;
    ConservativeHull out;
    const auto& params = setup.params;
    if (!(detail::conservativeFinite(clip0) && detail::conservativeFinite(clip1) && detail::conservativeFinite(clip2))) {
        out.kind = ConservativeHullKind::Dropped;
        return out;
    }
    const glm::vec2 size(params.viewport.z, params.viewport.w);
    const glm::vec2 half_size = 0.5f * size;
    float h = params.expansion.x;

    const glm::vec4 c[3] = {clip0, clip1, clip2};
    const bool inside = detail::conservativeVertexInside(c[0], params) && detail::conservativeVertexInside(c[1], params) &&
                        detail::conservativeVertexInside(c[2], params);
    glm::vec2 polygon[kConservativeMaxPolygon];
    float depth[kConservativeMaxPolygon];
    int n = 3;
    if (inside) {
        for (int i = 0; i < 3; ++i) {
            const glm::vec2 ndc = glm::vec2(c[i].x, c[i].y) / c[i].w;
            polygon[i] = glm::vec2(detail::conservativeMulRounded(ndc.x, half_size.x),
                                   detail::conservativeMulRounded(ndc.y, half_size.y)) + half_size;
            depth[i] = c[i].z / c[i].w;
        }
    } else {
        if (detail::conservativeOutsideOnePlane(c, params)) {
            out.kind = ConservativeHullKind::Culled;
            return out;
        }
        out.spilled = setup.spill.enabled;  // the direct pass hands it to the spill pass
        n = detail::conservativeClip(c, params, polygon, depth);
        if (n == 0) {
            out.kind = ConservativeHullKind::Culled;
            return out;
        }
    }

    const glm::vec2 origin = polygon[0];
    float area2 = 0.0f;
    for (int i = 1; i + 1 < n; ++i) area2 += conservativeCross(polygon[i] - origin, polygon[i + 1] - origin);
    float diameter2 = 0.0f;
    int far_a = 0, far_b = 0;
    for (int i = 0; i < n; ++i) {
        for (int j = i + 1; j < n; ++j) {
            const glm::vec2 d = polygon[j] - polygon[i];
            const float d2 = detail::conservativeLength2(d);
            if (d2 > diameter2) {
                diameter2 = d2;
                far_a = i;
                far_b = j;
            }
        }
    }
    const float diameter = std::sqrt(diameter2);
    const float thin_bound = detail::conservativeMulRounded(
        params.expansion.z + detail::conservativeMulRounded(params.expansion.w, diameter), diameter);
    const bool thin = std::abs(area2) <= thin_bound;
    if (thin && setup.options.drop_degenerate) {
        out.kind = ConservativeHullKind::Dropped;
        return out;
    }

    float z0 = depth[0];
    glm::vec2 gradient(0.0f);
    if (thin) {
        for (int i = 1; i < n; ++i) z0 = std::min(z0, depth[i]);
    } else {
        glm::vec3 normal(0.0f), mean(0.0f);
        for (int i = 0; i < n; ++i) {
            const glm::vec3 a(polygon[i] - origin, depth[i]);
            const int j = i + 1 < n ? i + 1 : 0;
            const glm::vec3 b(polygon[j] - origin, depth[j]);
            using detail::conservativeMulRounded;
            normal += glm::vec3(conservativeMulRounded(a.y - b.y, a.z + b.z), conservativeMulRounded(a.z - b.z, a.x + b.x),
                                conservativeMulRounded(a.x - b.x, a.y + b.y));
            mean += a;
        }
        mean /= static_cast<float>(n);
        gradient = -glm::vec2(normal.x, normal.y) / normal.z;
        z0 = mean.z - (detail::conservativeMulRounded(gradient.x, mean.x) + detail::conservativeMulRounded(gradient.y, mean.y));
    }

    if (thin) {
        const glm::vec2 a = polygon[far_a], b = polygon[far_b];
        float thickness = 0.0f;
        if (diameter > 0.0f) {
            for (int i = 0; i < n; ++i) thickness = std::max(thickness, std::abs(conservativeCross(polygon[i] - a, b - a)));
            thickness /= diameter;
        }
        h += thickness;
        polygon[0] = a;
        polygon[1] = b;
        n = 2;
    } else if (area2 < 0.0f) {
        std::reverse(polygon, polygon + n);
    }
    if (inside && !thin) out.triangle = {polygon[0], polygon[1], polygon[2]};
    out.dilation = h;

    glm::vec2 lo = polygon[0], hi = polygon[0];
    for (int i = 1; i < n; ++i) {
        lo = glm::min(lo, polygon[i]);
        hi = glm::max(hi, polygon[i]);
    }
    lo -= glm::vec2(h);
    hi += glm::vec2(h);
    if (lo.x > size.x || lo.y > size.y || hi.x < 0.0f || hi.y < 0.0f) {
        out.kind = ConservativeHullKind::Culled;
        return out;
    }
    out.box = glm::vec4(lo + glm::vec2(params.viewport.x, params.viewport.y), hi + glm::vec2(params.viewport.x, params.viewport.y));

    int count = -1;
    if (setup.options.variant == ConservativeVariant::Fixed6 && inside && !thin) {
        count = detail::conservativeFixedHull(polygon, h, out.pixels.data());
    } else {
        count = detail::conservativeChainHull(polygon, n, h, out.pixels.data());
    }
    out.kind = thin ? ConservativeHullKind::Thin : inside ? ConservativeHullKind::Triangle : ConservativeHullKind::Clipped;
    if (count < 0) {
        out.pixels[0] = lo;
        out.pixels[1] = glm::vec2(hi.x, lo.y);
        out.pixels[2] = hi;
        out.pixels[3] = glm::vec2(lo.x, hi.y);
        count = 4;
        out.kind = ConservativeHullKind::Fallback;
    }
    PENUMBRA_ASSERT(count <= kConservativeMaxVertices);
    // The direct pass declares 6: every hull it emits (unclipped triangle, thin hexagon or square,
    // box fallback) fits.
    PENUMBRA_ASSERT(!inside || setup.options.variant != ConservativeVariant::Fixed6 || count <= kConservativeFixed6MaxVertices);
    out.count = count;
    for (int j = 0; j < count; ++j) {
        const int index = (j & 1) != 0 ? (j + 1) >> 1 : (count - (j >> 1)) % count;
        const glm::vec2 q = out.pixels[static_cast<size_t>(index)];
        const glm::vec2 dq = q - origin;
        const float z = std::clamp(z0 + (detail::conservativeMulRounded(gradient.x, dq.x) + detail::conservativeMulRounded(gradient.y, dq.y)),
                                   params.depth.x, params.depth.y);
        out.positions[static_cast<size_t>(j)] = glm::vec4(q / half_size - 1.0f, z, 1.0f);
    }
    return out;
}

inline ConservativeHull conservativeHull(const glm::vec4 (&clip)[3], const ConservativeRasterSetup& setup) {
    return conservativeHull(clip[0], clip[1], clip[2], setup);
}

/// CPU twin of penumbraConservativeNeedsSpill: true when the Fixed-6 direct pass appends this
/// triangle to the spill buffer (finite, needs clipping, not entirely outside one clipping plane).
/// Independent of the variant; in the Exact variant's single pass these are the clipped ones.
inline bool conservativeNeedsSpill(const glm::vec4& clip0, const glm::vec4& clip1, const glm::vec4& clip2,
                                   const ConservativeRasterSetup& setup) {
    if (!(detail::conservativeFinite(clip0) && detail::conservativeFinite(clip1) && detail::conservativeFinite(clip2))) {
        return false;
    }
    const glm::vec4 c[3] = {clip0, clip1, clip2};
    if (detail::conservativeVertexInside(c[0], setup.params) && detail::conservativeVertexInside(c[1], setup.params) &&
        detail::conservativeVertexInside(c[2], setup.params)) {
        return false;
    }
    return !detail::conservativeOutsideOnePlane(c, setup.params);
}

/// The fragments GL's rule predicts for a hull (pixel centre strictly inside, or on an edge that
/// is a top or left edge), viewport-relative, with the fragment-stage box clip when the setup asks
/// for it. Pixels whose centre lies within `tolerance` pixels of the hull's boundary (or of the box)
/// go to `uncertain` instead: a rasterizer that snaps vertices to its subpixel grid may decide them
/// either way. Evaluated in double on the float hull vertices.
struct HullRaster {
    std::vector<glm::ivec2> fragments;  ///< predicted fragments (inside by more than `tolerance`)
    std::vector<glm::ivec2> uncertain;  ///< within `tolerance` of the boundary
};

namespace detail {

/// The convex hull (CCW, no repeated or collinear vertices) of `count` pixel-space vertices, in
/// double. An emitted polygon is convex up to float rounding, but a dilated hull around a cluster
/// of nearly equal points can come out with a reflex vertex a micro-pixel deep (two vertices
/// 4e-6 px apart, seen on a silhouette edge clipped just short of the far plane). GL rasterizes
/// the strip the geometry stage emits, whose triangles cover such a notch's neighbourhood; the
/// half-planes of the polygon's own edges would not (a micro-pixel edge's line cuts off a wedge of
/// the polygon). The hull differs from the strip's union only inside the notch, within any
/// tolerance a test gives.
inline std::vector<glm::dvec2> convexPixelHull(const glm::vec2* pixels, int count) {
    std::vector<glm::dvec2> p(pixels, pixels + std::max(count, 0));
    std::sort(p.begin(), p.end(), [](const glm::dvec2& a, const glm::dvec2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
    p.erase(std::unique(p.begin(), p.end()), p.end());
    if (p.size() < 3) return p;
    const auto cross = [](const glm::dvec2& o, const glm::dvec2& a, const glm::dvec2& b) {
        return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
    };
    std::vector<glm::dvec2> hull(2 * p.size());
    size_t k = 0;
    for (size_t i = 0; i < p.size(); ++i) {  // lower chain
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0.0) --k;
        hull[k++] = p[i];
    }
    for (size_t i = p.size() - 1, t = k + 1; i-- > 0;) {  // upper chain
        while (k >= t && cross(hull[k - 2], hull[k - 1], p[i]) <= 0.0) --k;
        hull[k++] = p[i];
    }
    hull.resize(k - 1);
    return hull;
}

/// GL's polygon rule on `count` CCW pixel-space vertices (centre strictly inside, or on a top or
/// left edge) over a width x height viewport, optionally clipped to `box` (x0, y0, x1, y1); centres
/// within `tolerance` of the boundary go to `uncertain`. Double on the float vertices, on their
/// convex hull (convexPixelHull). Shared by rasterizeConservativeHull and influenceRegionTexels.
inline HullRaster pixelRule(const glm::vec2* pixels, int count, int width, int height, const glm::dvec4* box,
                            double tolerance) {
    HullRaster out;
    const std::vector<glm::dvec2> hull = convexPixelHull(pixels, count);
    if (hull.size() < 3) return out;
    // Polygon edges in CCW order; distances are exact up to double rounding.
    struct Edge {
        glm::dvec2 a, n;  // point, unit outward normal
        bool top_left;
    };
    std::vector<Edge> edges;
    glm::dvec2 lo(1e300), hi(-1e300);
    for (size_t i = 0; i < hull.size(); ++i) {
        const glm::dvec2 a = hull[i];
        const glm::dvec2 b = hull[(i + 1) % hull.size()];
        lo = glm::min(lo, a);
        hi = glm::max(hi, a);
        const glm::dvec2 d = b - a;
        const double length = std::sqrt(glm::dot(d, d));
        if (length == 0.0) continue;
        // GL's top-left rule (CCW, y up): a top edge is horizontal with the interior below it
        // (going left), a left edge goes down.
        const bool top_left = (d.y == 0.0 && d.x < 0.0) || d.y < 0.0;
        edges.push_back({a, glm::dvec2(d.y, -d.x) / length, top_left});
    }
    const int x0 = std::max(0, static_cast<int>(std::floor(lo.x - 1.0)));
    const int y0 = std::max(0, static_cast<int>(std::floor(lo.y - 1.0)));
    const int x1 = std::min(width - 1, static_cast<int>(std::ceil(hi.x + 1.0)));
    const int y1 = std::min(height - 1, static_cast<int>(std::ceil(hi.y + 1.0)));
    for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
            const glm::dvec2 centre(x + 0.5, y + 0.5);
            bool inside = true;
            double nearest = 1e300;
            for (const Edge& e : edges) {
                const double outside = glm::dot(centre - e.a, e.n);  // > 0: outside this edge
                nearest = std::min(nearest, std::abs(outside));
                if (outside > 0.0 || (outside == 0.0 && !e.top_left)) inside = false;
            }
            if (box) {
                const double box_distance = std::min(std::min(centre.x - box->x, box->z - centre.x),
                                                     std::min(centre.y - box->y, box->w - centre.y));
                nearest = std::min(nearest, std::abs(box_distance));
                if (box_distance < 0.0) inside = false;
            }
            if (nearest < tolerance) {
                out.uncertain.emplace_back(x, y);
            } else if (inside) {
                out.fragments.emplace_back(x, y);
            }
        }
    }
    return out;
}

}  // namespace detail

inline HullRaster rasterizeConservativeHull(const ConservativeHull& hull, const ConservativeRasterSetup& setup,
                                            double tolerance = 0.0) {
    const glm::dvec2 origin(setup.params.viewport.x, setup.params.viewport.y);
    const glm::dvec4 box = glm::dvec4(hull.box) - glm::dvec4(origin, origin);
    return detail::pixelRule(hull.pixels.data(), hull.count, setup.width(), setup.height(),
                             setup.options.clip_to_box ? &box : nullptr, tolerance);
}

/// CPU twin of penumbraConservativeBoxPixels (conservative_raster_clip.glsl): the window pixels
/// (x0, y0) .. (x1, y1), inclusive, of `viewport` (x, y, width, height) whose centres the hull's
/// box may hold, one more on each side, clipped to the viewport (x1 < x0 or y1 < y0: none). The
/// compute light passes visit these and keep those whose centre passes the box test. `box` is a
/// hull's that was not dropped (within the guard band).
inline glm::ivec4 conservativeBoxPixels(const glm::vec4& box, const glm::ivec4& viewport) {
    const glm::ivec2 lo = glm::max(glm::ivec2(std::floor(box.x), std::floor(box.y)) - 1, glm::ivec2(viewport.x, viewport.y));
    const glm::ivec2 hi = glm::min(glm::ivec2(std::floor(box.z), std::floor(box.w)) + 1,
                                   glm::ivec2(viewport.x + viewport.z - 1, viewport.y + viewport.w - 1));
    return glm::ivec4(lo, hi);
}

/// CPU twin of penumbraConservativeInsideDilatedTriangle (conservative_raster_clip.glsl): does the
/// point `centre` (viewport-relative pixels) lie in the counter-clockwise triangle `t` dilated by
/// the square [-h, h]^2 within its edges' half-planes? Together with the box (the square's own
/// sides) that is the exact hull's region. In double: every edge vector and difference of floats
/// is exact there, so each side test rounds once (a relative slack of 1e-9 covers it).
inline bool conservativeInsideDilatedTriangle(const glm::vec2& centre, const std::array<glm::vec2, 3>& t, float h) {
    for (int i = 0; i < 3; ++i) {
        const glm::dvec2 a(t[size_t(i)]), b(t[size_t((i + 1) % 3)]);
        const glm::dvec2 n(b.y - a.y, a.x - b.x);  // outward normal of a counter-clockwise edge
        const double side = n.x * (double(centre.x) - a.x) + n.y * (double(centre.y) - a.y);
        const double support = double(h) * (std::abs(n.x) + std::abs(n.y));
        if (side > support * (1.0 + 1e-9)) return false;
    }
    return true;
}

/// CPU twin of penumbraConservativeRectMeetsDilatedTriangle: false only when no point of the
/// rectangle [lo, hi] passes conservativeInsideDilatedTriangle(point, t, h) (each edge's smallest
/// side value over the rectangle is at the corner its normal points away from).
inline bool conservativeRectMeetsDilatedTriangle(const glm::vec2& lo, const glm::vec2& hi, const std::array<glm::vec2, 3>& t,
                                                 float h) {
    for (int i = 0; i < 3; ++i) {
        const glm::dvec2 a(t[size_t(i)]), b(t[size_t((i + 1) % 3)]);
        const glm::dvec2 n(b.y - a.y, a.x - b.x);
        const glm::vec2 corner(n.x > 0.0 ? lo.x : hi.x, n.y > 0.0 ? lo.y : hi.y);
        const double side = n.x * (double(corner.x) - a.x) + n.y * (double(corner.y) - a.y);
        const double support = double(h) * (std::abs(n.x) + std::abs(n.y));
        if (side > support * (1.0 + 1e-9)) return false;
    }
    return true;
}

/// Ground truth, part 1: the triangle clipped to the near plane and w >= min_w (and, to keep the
/// numbers small, to a guard band 2^20 pixels around the viewport — far enough never to change a
/// viewport pixel), projected to viewport-relative pixels, in double. Empty for NaN/Inf input or
/// when nothing is in front of the near plane. Independent of the emitter's clipping code.
inline std::vector<glm::dvec2> conservativeReferencePolygon(const glm::vec4& clip0, const glm::vec4& clip1,
                                                            const glm::vec4& clip2, const ConservativeRasterSetup& setup) {
    std::vector<glm::dvec2> out;
    if (!(detail::conservativeFinite(clip0) && detail::conservativeFinite(clip1) && detail::conservativeFinite(clip2))) {
        return out;
    }
    const double w = setup.params.viewport.z, h = setup.params.viewport.w;
    const double far_guard = 1048576.0;
    const glm::dvec4 planes[6] = {glm::dvec4(setup.options.near_plane),
                                  glm::dvec4(0, 0, 0, 1),  // w >= min_w: offset below
                                  glm::dvec4(1, 0, 0, 1 + 2 * far_guard / w), glm::dvec4(-1, 0, 0, 1 + 2 * far_guard / w),
                                  glm::dvec4(0, 1, 0, 1 + 2 * far_guard / h), glm::dvec4(0, -1, 0, 1 + 2 * far_guard / h)};
    const double offsets[6] = {0, -static_cast<double>(setup.options.min_w), 0, 0, 0, 0};
    std::vector<glm::dvec4> poly = {glm::dvec4(clip0), glm::dvec4(clip1), glm::dvec4(clip2)}, next;
    for (int k = 0; k < 6 && !poly.empty(); ++k) {
        next.clear();
        for (size_t i = 0; i < poly.size(); ++i) {
            const glm::dvec4& a = poly[(i + poly.size() - 1) % poly.size()];
            const glm::dvec4& b = poly[i];
            // Products opaque (detail::conservativeMulRounded): the same bits under any FMA flags.
            auto side = [&](const glm::dvec4& q) {
                const glm::dvec4& n = planes[k];
                double d = detail::conservativeMulRounded(n.x, q.x) + detail::conservativeMulRounded(n.y, q.y);
                d = d + detail::conservativeMulRounded(n.z, q.z);
                d = d + detail::conservativeMulRounded(n.w, q.w);
                return d + offsets[k];
            };
            auto along = [](const glm::dvec4& from, double t, const glm::dvec4& to) {
                const glm::dvec4 d = to - from;
                return from + glm::dvec4(detail::conservativeMulRounded(t, d.x), detail::conservativeMulRounded(t, d.y),
                                         detail::conservativeMulRounded(t, d.z), detail::conservativeMulRounded(t, d.w));
            };
            const double da = side(a), db = side(b);
            // Intersections from the kept end, so their error scales with the kept coordinates.
            if (da >= 0 && db < 0) next.push_back(along(a, da / (da - db), b));
            if (da < 0 && db >= 0) next.push_back(along(b, db / (db - da), a));
            if (db >= 0) next.push_back(b);
        }
        poly.swap(next);
    }
    for (const auto& c : poly) {
        out.emplace_back(detail::conservativeMulRounded((c.x / c.w + 1.0) * 0.5, w),
                         detail::conservativeMulRounded((c.y / c.w + 1.0) * 0.5, h));
    }
    return out;
}

/// Ground truth, part 2: does the closed convex polygon (any winding; segments and points allowed)
/// intersect the closed pixel square [x, x+1] x [y, y+1]? Separating axis test in double on the
/// box axes and every polygon edge normal, in coordinates relative to the pixel (touching counts:
/// only a strict gap separates).
inline bool polygonTouchesPixel(const glm::dvec2* polygon, size_t count, int x, int y) {
    if (count == 0) return false;
    const glm::dvec2 pixel(x, y);
    glm::dvec2 lo(1e300), hi(-1e300);
    for (size_t i = 0; i < count; ++i) {
        lo = glm::min(lo, polygon[i] - pixel);
        hi = glm::max(hi, polygon[i] - pixel);
    }
    if (hi.x < 0.0 || lo.x > 1.0 || hi.y < 0.0 || lo.y > 1.0) return false;
    for (size_t i = 0; i < count; ++i) {
        const glm::dvec2 a = polygon[i] - pixel, b = polygon[(i + 1) % count] - pixel;
        const glm::dvec2 n(b.y - a.y, a.x - b.x);
        if (n.x == 0.0 && n.y == 0.0) continue;
        double poly_lo = 1e300, poly_hi = -1e300;
        for (size_t k = 0; k < count; ++k) {
            const double s = glm::dot(n, polygon[k] - pixel);
            poly_lo = std::min(poly_lo, s);
            poly_hi = std::max(poly_hi, s);
        }
        // The square's projection: corners (0,0), (1,0), (0,1), (1,1).
        const double box_lo = std::min(0.0, n.x) + std::min(0.0, n.y);
        const double box_hi = std::max(0.0, n.x) + std::max(0.0, n.y);
        if (poly_hi < box_lo || poly_lo > box_hi) return false;
    }
    return true;
}

inline bool triangleTouchesPixel(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c, int x, int y) {
    const glm::dvec2 tri[3] = {a, b, c};
    return polygonTouchesPixel(tri, 3, x, y);
}

/// Ground truth, part 3: every viewport pixel the contract requires for this triangle
/// (viewport-relative), row-major order.
inline std::vector<glm::ivec2> conservativeRequiredPixels(const glm::vec4& clip0, const glm::vec4& clip1,
                                                          const glm::vec4& clip2, const ConservativeRasterSetup& setup) {
    std::vector<glm::ivec2> out;
    const std::vector<glm::dvec2> poly = conservativeReferencePolygon(clip0, clip1, clip2, setup);
    if (poly.empty()) return out;
    glm::dvec2 lo(1e300), hi(-1e300);
    for (const auto& q : poly) {
        lo = glm::min(lo, q);
        hi = glm::max(hi, q);
    }
    // Pixel i's square touches [lo, hi] iff i <= hi and i + 1 >= lo.
    const double x0 = std::max(0.0, std::ceil(lo.x) - 1.0), y0 = std::max(0.0, std::ceil(lo.y) - 1.0);
    const double x1 = std::min(static_cast<double>(setup.width() - 1), std::floor(hi.x));
    const double y1 = std::min(static_cast<double>(setup.height() - 1), std::floor(hi.y));
    for (double y = y0; y <= y1; ++y) {
        for (double x = x0; x <= x1; ++x) {
            if (polygonTouchesPixel(poly.data(), poly.size(), static_cast<int>(x), static_cast<int>(y))) {
                out.emplace_back(static_cast<int>(x), static_cast<int>(y));
            }
        }
    }
    return out;
}

}  // namespace penumbra

#endif
