// penumbra — convex-hull influence regions of shadow-casting triangles (sintorn2008 §4.1, Fig. 5;
// the optional supporting-plane cut of §4.3 after [LLA06]) and their conservative rasterization
// into the light grid (the corner rules of §4.1 on top of the §3.2 emitter's polygon code).
//
// Integration summary
//   needs:    the light (penumbra::Light: sphere, ellipsoid, disk, rectangle), the light grid's
//             view-projection (a perspective projection from a point inside the light, e.g.
//             lightViewProjectionForBounds from the light centre; SampleListsLight::view_projection),
//             its size W x H, and a far plane that lies beyond every receiver (influenceFarPlaneAtDepth:
//             the plane at the farthest view sample's light depth, §4.3; or a user plane: a floor).
//   produces: influenceRegionSetup() -> the PenumbraInfluenceParams block (std140) and the #define
//             permutation (PENUMBRA_INFLUENCE_SIDES = k, PENUMBRA_INFLUENCE_CUT) (pure C++, no GL);
//             GLSL snippet penumbra/influence_region/influence_region.glsl with
//               int penumbraInfluenceRegion(vec3 v0, vec3 v1, vec3 v2, PenumbraInfluenceParams p)
//             filling penumbraInfluenceOut[] (grid pixels, counter-clockwise) and
//             penumbraInfluenceKind / penumbraInfluenceFallback; ready entries
//             influence_region.geom.glsl (emits the polygon as a strip into the W x H viewport) and
//             influence_region.frag.glsl (marks covered texels in a bitset: the tests' recorder);
//             vertex stage: conservative_raster.vert.glsl (attribute 0 = world position, w = 1);
//             CPU twin influenceRegion() (same float operations, bit for bit on llvmpipe),
//             influenceRegionTexels() (GL's pixel-centre rule on it), and the exact predicate
//             influenceShadowedContinuous() (continuous light, closest approach, double).
//   hooks:    none in the snippet (it returns the polygon; the entry emits it).
//
// Contract (what "never miss" means; tests/influence_region_test.cpp checks it on >= 10^5 random
// and adversarial cases). Let o be the grid's projection centre, F the far plane, L the light.
// Every receiver p with clip.w(p) > 0 lying between o's plane parallel to F and F (s(o) < s(p) <= 0
// for the far plane's signed distance s) that is shadowed by the triangle from SOME point of L
// (the segment p-y meets the closed triangle for some y in L) projects into a texel that receives
// a fragment — unless the triangle is dropped (NaN/Inf vertex: then nothing is promised). Why:
// the shadow set S = {y + s (x - y): y in L, x in T, s >= 1} is star-shaped outwards from any
// point of L: for p in S and lambda >= 1, o + lambda (p - o) = y' + s' (x - y') with
// y' = o + mu (y - o), mu = lambda (s - 1) / (lambda s - 1) in [0, 1], s' = lambda s, so y' is in
// L when L is convex and holds o. Hence p's texel ray meets F in a point of S n F: the union of T's
// projections onto F from all light points, which lies in the convex hull of the projections of
// the light through T's vertices, each of which lies inside the projection of the k-gon that
// circumscribes the light's silhouette circle seen from that vertex (the cone over the k-gon holds
// the cone over the ball). So the hull of the 3k far points holds every shadowed texel ray.
//
// The construction, per triangle (float, the same operations on both sides):
//   1. vertices to the light's normalised space q = S^-1 R^T (v - c) (sintorn2008 §4.1's scaling
//      trick: an ellipsoid becomes the unit ball). Disks and rectangles are bounded by the unit
//      ball too (documented fallback: their exact outline is not used yet).
//   2. per vertex: the silhouette of the ball of radius R = 1 + 2^-10 + 2^-17 |q| (inflated to
//      absorb float error) seen from q is the circle of centre q R^2/|q|^2 and radius
//      R sqrt(|q|^2 - R^2) / |q| in the plane perpendicular to q; a regular k-gon of circumradius
//      radius / cos(pi / k) circumscribes it; the line from each k-gon vertex g through q meets F at
//      f = q + t (q - g), t = -s(q) / (n . (q - g)). In grid-pixel homogeneous coordinates that is
//      P = (n . d) C(q) - s(q) D(d), d = q - g, with C, D the homogeneous images of the point q and
//      the direction d: no division until the pixel (P.xy / P.w), so far points never overflow;
//   3. fallbacks to the whole grid (kind WHOLE_GRID, flag bits say why): a vertex on/beyond F while
//      another is in front (all beyond: culled, they cannot shadow anything in front of F), a vertex
//      within 1 + 2^-8 light radii of the centre, a vertex at/behind the eye plane or projecting
//      outside the guard band (|x|, |y| > B w), a ray that does not reach F or heads back towards the
//      eye plane (n . d <= 0 or D.w <= 0) or whose vanishing point lies outside the guard band. The
//      guard band keeps every pixel coordinate within B = max(W, H) + G, so the float error of every
//      hull vertex is a few ulps of B, which the margin covers;
//   4. the convex hull of the 3k points by merging: each vertex's k points are in angular order
//      (a convex polygon, either orientation); splitting it at its leftmost and rightmost point
//      gives two x-monotone chains, merged in O(k); the three sorted groups are merged in O(k)
//      (two 2-way merges); an insertion pass repairs any order rounding broke (O(k) when there is
//      none); Andrew's monotone chain builds the hull of the sorted points in O(k). Total O(k);
//   5. optional cut (PENUMBRA_INFLUENCE_CUT, sintorn2008 §4.3 / [LLA06]): when the light's ball lies
//      strictly on one side of the triangle's supporting plane (clearance 1 + 2^-8 + 2^-16 |q0| radii,
//      non-sliver triangles only), only texel rays from o that cross that plane can hold a shadowed
//      receiver: a half-plane in grid pixels (the line depends only on the plane's normal), which
//      clips the hull (offset outwards by the margin);
//   6. conservative rasterization: the hull dilated by the square [-h, h]^2, h = 0.5 + margin
//      (margin = 2^-subpixel_bits + 2^-17 B + extra_margin), with the §4.1 corner rules on the
//      emitter's corner code (detail::conservativeCorner / conservativeEdgeCorner): case i (both
//      edges supported by one square corner) one vertex; case ii (adjacent corners) the
//      intersection of the two offset edges when the turn between the edges is below 90° (and not
//      so small that the intersection is ill-conditioned: sin >= 2^-6), else the two corners;
//      case iii (diagonal corners) the three corners. A degenerate hull (< 3 vertices) or an
//      inconsistent turn sequence falls back to the pixel-expanded bounding box (kind BOX). GL's
//      pixel-centre rule on the dilated polygon then covers every texel whose square the hull touches.
//
// Bad input -> penumbra::Error at setup naming the value: grid size, k not in {4, 6, 8, 12}, a bad
// light (penumbra::lightFrame's checks: non-finite, zero radius ...), a non-finite or non-projective
// view-projection, a projection centre outside the light, a far plane that is not finite, has no
// normal, touches the light, or lies behind the light (facing away from the grid's view direction).
#ifndef PENUMBRA_INFLUENCE_REGION_HPP
#define PENUMBRA_INFLUENCE_REGION_HPP

#include "penumbra/conservative_raster.hpp"
#include "penumbra/detail/float_ops.hpp"
#include "penumbra/detail/geometry.hpp"
#include "penumbra/detail/shared.hpp"
#include "penumbra/error.hpp"
#include "penumbra/light_samples.hpp"
#include "penumbra/shader_defines.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace penumbra::shared {
#if defined(__has_include) && __has_include(<penumbra/influence_region/influence_region_shared.h>)
#include <penumbra/influence_region/influence_region_shared.h>
#else
#include "../../shaders/penumbra/influence_region/influence_region_shared.h"
#endif
}  // namespace penumbra::shared

namespace penumbra {

using InfluenceRegionParams = shared::PenumbraInfluenceParams;
static_assert(sizeof(InfluenceRegionParams) == 21 * 16, "std140 layout the shaders assume: 20 vec4 + 1 uvec4");

inline constexpr int kInfluenceMaxSides = PENUMBRA_INFLUENCE_MAX_SIDES;
inline constexpr int kInfluenceMaxPoints = PENUMBRA_INFLUENCE_MAX_POINTS(PENUMBRA_INFLUENCE_MAX_SIDES);
inline constexpr int kInfluenceMaxPolygon = PENUMBRA_INFLUENCE_MAX_POLYGON(PENUMBRA_INFLUENCE_MAX_SIDES);
inline constexpr int kInfluenceMaxVertices = PENUMBRA_INFLUENCE_MAX_VERTICES(PENUMBRA_INFLUENCE_MAX_SIDES);
/// Largest grid side (as the conservative emitter).
inline constexpr int kInfluenceMaxGrid = kConservativeMaxViewport;
/// Float error allowance per pixel of guard bound B: 128 ulps (the hull vertices come out of a
/// local transform, the k-gon, a 3-term homogeneous combination and a division; each a few ulps).
inline constexpr float kInfluenceFloatSlack = 1.0f / 131072.0f;  // 2^-17
/// Inflation of the light's bounding ball: R = 1 + kInfluenceInflation + kInfluenceInflationPerUnit |q|.
inline constexpr float kInfluenceInflation = 1.0f / 1024.0f;
inline constexpr float kInfluenceInflationPerUnit = 1.0f / 131072.0f;
/// A vertex within this many light radii of the centre falls back to the whole grid.
inline constexpr float kInfluenceInsideRadius = 1.0f + 1.0f / 256.0f;
/// Supporting-plane cut: the plane must clear the light by 1 + 2^-8 + 2^-16 |q0| radii.
inline constexpr float kInfluenceCutClearance = 1.0f + 1.0f / 256.0f;
inline constexpr float kInfluenceCutClearancePerUnit = 1.0f / 65536.0f;

enum class InfluenceRegionKind : int {
    Dropped = PENUMBRA_INFLUENCE_KIND_DROPPED,      ///< NaN/Inf vertex: nothing
    Culled = PENUMBRA_INFLUENCE_KIND_CULLED,        ///< beyond F, cut away, or entirely off the grid
    Hull = PENUMBRA_INFLUENCE_KIND_HULL,            ///< dilated convex hull
    Box = PENUMBRA_INFLUENCE_KIND_BOX,              ///< pixel-expanded bounding box of a degenerate hull
    WholeGrid = PENUMBRA_INFLUENCE_KIND_WHOLE_GRID, ///< documented fallback: the grid rectangle
};

inline const char* influenceRegionKindName(InfluenceRegionKind kind) {
    switch (kind) {
        case InfluenceRegionKind::Dropped: return "dropped";
        case InfluenceRegionKind::Culled: return "culled";
        case InfluenceRegionKind::Hull: return "hull";
        case InfluenceRegionKind::Box: return "box";
        case InfluenceRegionKind::WholeGrid: return "whole grid";
    }
    return "?";
}

/// Value-initialised = defaults, except the grid size and the far plane, which must be given.
struct InfluenceRegionOptions {
    int grid_width = 0;   ///< light grid W (1 .. kInfluenceMaxGrid)
    int grid_height = 0;  ///< light grid H
    int sides = PENUMBRA_INFLUENCE_DEFAULT_SIDES;  ///< k: 4, 6 (sintorn2008 §4.1's hexagon), 8 or 12
    /// World plane dot(n, p) + w = 0 beyond every receiver (see influenceFarPlaneAtDepth). Either
    /// orientation; the side holding the light is "in front".
    glm::dvec4 far_plane{0.0};
    bool cut_by_supporting_plane = false;  ///< sintorn2008 §4.3 / [LLA06]
    int subpixel_bits = 4;       ///< the driver's GL_SUBPIXEL_BITS (1..16); 4 = GL's minimum
    float extra_margin = 0.0f;   ///< pixels added to the margin (0..16)
    float guard_band = 0.0f;     ///< G (px): hull points within B = max(W, H) + G; 0 = 2 max(W, H)
};

/// What influenceRegionSetup derived; `params` go to the shaders (std140), `defines` to the programs.
struct InfluenceRegionSetup {
    InfluenceRegionParams params{};
    ShaderDefines defines;
    InfluenceRegionOptions options;
    /// The light's frame moved to the float centre the shaders use (params.center); the ball is
    /// inflated by that move. toLocal / toWorld of the region's geometry use this frame.
    LightFrame frame;
    LightShape shape = LightShape::Sphere;
    float margin = 0.0f;     ///< pixels beyond the half-pixel dilation
    float half_size = 0.0f;  ///< h
    float bound = 0.0f;      ///< B
    int max_vertices = 0;    ///< the geometry stage's max_vertices: 3k + 5
    // Double copies for the exact side of the tests (the float params are their roundings).
    glm::dvec3 projection_center_local{0.0};  ///< o in local space
    glm::dmat4 local_to_clip{1.0};            ///< VP * [R S | c] (from the float VP)
    glm::dvec4 far_plane_local{0.0};          ///< unit normal, offset; light side negative

    int width() const { return options.grid_width; }
    int height() const { return options.grid_height; }
    int sides() const { return options.sides; }
};

/// The world plane at light depth `depth` (clip.w = depth) of a perspective view-projection: the
/// §4.3 far plane "perpendicular to the light's view axis at the farthest view sample's distance".
inline glm::dvec4 influenceFarPlaneAtDepth(const glm::mat4& view_projection, double depth) {
    PENUMBRA_CHECK(std::isfinite(depth) && depth > 0.0, "penumbra::influenceFarPlaneAtDepth: depth = ", depth,
                   " must be finite and > 0");
    return glm::dvec4(view_projection[0][3], view_projection[1][3], view_projection[2][3],
                      static_cast<double>(view_projection[3][3]) - depth);
}

namespace detail {

inline float influenceDot3(const glm::vec4& a, const glm::vec3& b) {
    return (mulRounded(a.x, b.x) + mulRounded(a.y, b.y)) + mulRounded(a.z, b.z);
}
inline float influenceDot3(const glm::vec3& a, const glm::vec3& b) {
    return (mulRounded(a.x, b.x) + mulRounded(a.y, b.y)) + mulRounded(a.z, b.z);
}
// (row . (q, 1)): ((x q.x + y q.y) + z q.z) + w.
inline float influenceAffine(const glm::vec4& row, const glm::vec3& q) { return influenceDot3(row, q) + row.w; }
inline glm::vec3 influenceCross(const glm::vec3& a, const glm::vec3& b) {
    return glm::vec3(mulRounded(a.y, b.z) - mulRounded(a.z, b.y), mulRounded(a.z, b.x) - mulRounded(a.x, b.z),
                     mulRounded(a.x, b.y) - mulRounded(a.y, b.x));
}
inline glm::vec3 influenceScale(const glm::vec3& v, float s) {
    return glm::vec3(mulRounded(v.x, s), mulRounded(v.y, s), mulRounded(v.z, s));
}
inline float influenceCross2(const glm::vec2& a, const glm::vec2& b) { return mulRounded(a.x, b.y) - mulRounded(a.y, b.x); }
inline bool influenceLess(const glm::vec2& a, const glm::vec2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

inline float roundUpToFloat(double x) {
    float f = static_cast<float>(x);
    if (static_cast<double>(f) < x) f = std::nextafter(f, 2.0f * f + 1.0f);
    return f;
}

// Double helpers of the setup with every product opaque: the setup gives the same bits whatever
// the compiler's contraction flags (tests/twin_digest.cpp), so GPU == twin holds for any build.
inline glm::dvec3 influenceMul(const glm::dmat3& m, const glm::dvec3& v) {  // m * v
    glm::dvec3 r;
    for (int i = 0; i < 3; ++i) r[i] = (mulRounded(m[0][i], v.x) + mulRounded(m[1][i], v.y)) + mulRounded(m[2][i], v.z);
    return r;
}
inline glm::dmat4 influenceMul(const glm::dmat4& a, const glm::dmat4& b) {  // a * b
    glm::dmat4 r;
    for (int c = 0; c < 4; ++c)
        for (int i = 0; i < 4; ++i)
            r[c][i] = ((mulRounded(a[0][i], b[c][0]) + mulRounded(a[1][i], b[c][1])) + mulRounded(a[2][i], b[c][2])) +
                      mulRounded(a[3][i], b[c][3]);
    return r;
}
inline double det3(const glm::dmat3& m) {
    const double c0 = mulRounded(m[1][1], m[2][2]) - mulRounded(m[2][1], m[1][2]);
    const double c1 = mulRounded(m[2][1], m[0][2]) - mulRounded(m[0][1], m[2][2]);
    const double c2 = mulRounded(m[0][1], m[1][2]) - mulRounded(m[1][1], m[0][2]);
    return (mulRounded(m[0][0], c0) + mulRounded(m[1][0], c1)) + mulRounded(m[2][0], c2);
}
inline glm::dmat3 influenceInverse(const glm::dmat3& m) {  // adjugate / determinant
    const double d = det3(m);
    glm::dmat3 r;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            // r[j][i] = cofactor of m[i][j] / d (column-major: r = adj(m) / det)
            const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
            r[j][i] = (mulRounded(m[i1][j1], m[i2][j2]) - mulRounded(m[i2][j1], m[i1][j2])) / d;
        }
    }
    return r;
}

}  // namespace detail

/// Pure setup: validates and derives the parameter block. Throws penumbra::Error naming the value.
inline InfluenceRegionSetup influenceRegionSetup(const Light& light, const glm::mat4& view_projection,
                                                 const InfluenceRegionOptions& options) {
    const auto& o = options;
    PENUMBRA_CHECK(o.grid_width >= 1 && o.grid_width <= kInfluenceMaxGrid, "penumbra: influenceRegionSetup: grid_width = ",
                   o.grid_width, " must be in [1, ", kInfluenceMaxGrid, "]");
    PENUMBRA_CHECK(o.grid_height >= 1 && o.grid_height <= kInfluenceMaxGrid,
                   "penumbra: influenceRegionSetup: grid_height = ", o.grid_height, " must be in [1, ", kInfluenceMaxGrid, "]");
    PENUMBRA_CHECK(o.sides == 4 || o.sides == 6 || o.sides == 8 || o.sides == 12, "penumbra: influenceRegionSetup: sides = ",
                   o.sides, " must be 4, 6, 8 or 12");
    PENUMBRA_CHECK(o.subpixel_bits >= 1 && o.subpixel_bits <= 16, "penumbra: influenceRegionSetup: subpixel_bits = ",
                   o.subpixel_bits, " must be in [1, 16] (query GL_SUBPIXEL_BITS)");
    PENUMBRA_CHECK(std::isfinite(o.extra_margin) && o.extra_margin >= 0.0f && o.extra_margin <= 16.0f,
                   "penumbra: influenceRegionSetup: extra_margin = ", o.extra_margin, " must be in [0, 16] pixels");
    PENUMBRA_CHECK(std::isfinite(o.guard_band) && (o.guard_band == 0.0f || (o.guard_band >= 1.0f &&
                   o.guard_band <= 4.0f * static_cast<float>(kInfluenceMaxGrid))),
                   "penumbra: influenceRegionSetup: guard_band = ", o.guard_band, " must be 0 (default) or in [1, ",
                   4 * kInfluenceMaxGrid, "] pixels");
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) {
            PENUMBRA_CHECK(std::isfinite(view_projection[c][r]), "penumbra: influenceRegionSetup: view_projection[", c, "][",
                           r, "] = ", view_projection[c][r], " is not finite");
        }
    }
    const glm::dvec4& fp = o.far_plane;
    PENUMBRA_CHECK(std::isfinite(fp.x) && std::isfinite(fp.y) && std::isfinite(fp.z) && std::isfinite(fp.w),
                   "penumbra: influenceRegionSetup: far_plane = (", fp.x, ", ", fp.y, ", ", fp.z, ", ", fp.w,
                   ") is not finite");
    PENUMBRA_CHECK(fp.x != 0.0 || fp.y != 0.0 || fp.z != 0.0, "penumbra: influenceRegionSetup: far_plane = (", fp.x, ", ",
                   fp.y, ", ", fp.z, ", ", fp.w, ") has no normal (give one, e.g. influenceFarPlaneAtDepth)");

    InfluenceRegionSetup s;
    s.options = o;
    s.shape = light.shape;
    // The block works around the float light centre the GPU subtracts (params.center): the frame
    // is moved there and the ball inflated by the move (in units of the smallest semi-axis), so a
    // centre that is not a float stays covered.
    const LightFrame true_frame = lightFrame(light);  // throws naming the bad light value
    s.frame = true_frame;
    s.frame.center = glm::dvec3(detail::opaque(static_cast<float>(true_frame.center.x)),
                                detail::opaque(static_cast<float>(true_frame.center.y)),
                                detail::opaque(static_cast<float>(true_frame.center.z)));
    const double smallest_axis = std::min(true_frame.scale.x, std::min(true_frame.scale.y, true_frame.scale.z));
    const glm::dvec3 shift = true_frame.center - s.frame.center;
    const double centre_shift = std::sqrt(detail::dotRounded(shift, shift)) / smallest_axis;
    PENUMBRA_CHECK(std::isfinite(s.frame.center.x) && std::isfinite(s.frame.center.y) && std::isfinite(s.frame.center.z) &&
                   centre_shift < 0.25, "penumbra: influenceRegionSetup: light.center (", light.center.x, ", ", light.center.y,
                   ", ", light.center.z, ") is too far from the origin for a light of this size in float (rounding moves it ",
                   centre_shift, " light radii): pass light-relative coordinates");
    const LightFrame& frame = s.frame;

    // The projection centre o: rows x, y and w of the view-projection vanish there.
    const glm::dmat4 vp(view_projection);
    glm::dmat3 m3;
    glm::dvec3 rhs;
    const int rows[3] = {0, 1, 3};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) m3[j][i] = vp[j][rows[i]];
        rhs[i] = -vp[3][rows[i]];
    }
    double scale3 = 0.0;
    for (int j = 0; j < 3; ++j) scale3 = std::max(scale3, std::sqrt(detail::dotRounded(m3[j], m3[j])));
    const double det = detail::det3(m3);
    PENUMBRA_CHECK(std::isfinite(det) && std::abs(det) > 1e-12 * scale3 * scale3 * scale3,
                   "penumbra: influenceRegionSetup: view_projection is not a perspective projection from a point "
                   "(rows x, y, w are singular, determinant ", det, ")");
    const glm::dvec3 eye = detail::influenceMul(detail::influenceInverse(m3), rhs);
    s.projection_center_local = frame.toLocal(eye);
    const double eye_local = std::sqrt(detail::dotRounded(s.projection_center_local, s.projection_center_local));
    PENUMBRA_CHECK(eye_local <= 1.0, "penumbra: influenceRegionSetup: the light grid's projection centre (", eye.x, ", ",
                   eye.y, ", ", eye.z, ") lies outside the light (", eye_local,
                   " light radii from its centre): project the grid from inside the light (its centre)");

    // Far plane, local, oriented so that the light's centre is on the negative side.
    glm::dvec4 far_local = frame.planeToLocal(fp);
    PENUMBRA_CHECK(std::abs(far_local.w) > 1.0, "penumbra: influenceRegionSetup: far_plane = (", fp.x, ", ", fp.y, ", ",
                   fp.z, ", ", fp.w, ") touches the light (", std::abs(far_local.w), " light radii from its centre)");
    if (far_local.w > 0.0) far_local = -far_local;
    // The view direction in local space: the gradient of clip.w (row 3) pulled back through R S.
    const glm::dvec3 row_w(vp[0][3], vp[1][3], vp[2][3]);
    glm::dmat3 rs = frame.rotation;  // R S: columns scaled
    for (int j = 0; j < 3; ++j) rs[j] *= frame.scale[j];
    const glm::dvec3 view_local = detail::influenceMul(glm::transpose(rs), row_w);
    PENUMBRA_CHECK(detail::dotRounded(view_local, glm::dvec3(far_local)) > 0.0, "penumbra: influenceRegionSetup: far_plane = (",
                   fp.x, ", ", fp.y, ", ", fp.z, ", ", fp.w,
                   ") is behind the light: it must face the light grid's view direction");
    s.far_plane_local = far_local;

    // Local -> clip -> grid pixels (homogeneous).
    glm::dmat4 to_world(1.0);
    for (int j = 0; j < 3; ++j) to_world[j] = glm::dvec4(rs[j], 0.0);
    to_world[3] = glm::dvec4(frame.center, 1.0);
    s.local_to_clip = detail::influenceMul(vp, to_world);
    const double W = o.grid_width, H = o.grid_height;
    glm::dvec4 pixel_rows[3];
    for (int j = 0; j < 4; ++j) {
        const glm::dvec4& col = s.local_to_clip[j];
        pixel_rows[0][j] = 0.5 * W * (col[0] + col[3]);
        pixel_rows[1][j] = 0.5 * H * (col[1] + col[3]);
        pixel_rows[2][j] = col[3];
    }
    glm::dmat3 linear;  // linear[col][row]
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) linear[c][r] = pixel_rows[r][c];
    const glm::dmat3 cut = glm::transpose(detail::influenceInverse(linear));  // maps a local normal to a pixel line

    // The world -> local rows: S^-1 R^T.
    glm::dmat3 to_local_m = glm::transpose(frame.rotation);  // rows = R columns
    auto& p = s.params;
    p.center = glm::vec4(glm::vec3(frame.center), 0.0f);
    for (int r = 0; r < 3; ++r) {
        const glm::dvec3 row = glm::dvec3(to_local_m[0][r], to_local_m[1][r], to_local_m[2][r]) / frame.scale[r];
        p.to_local[r] = glm::vec4(glm::vec3(row), 0.0f);
        p.to_pixel[r] = glm::vec4(pixel_rows[r]);
        p.cut_lines[r] = glm::vec4(static_cast<float>(cut[0][r]), static_cast<float>(cut[1][r]),
                                   static_cast<float>(cut[2][r]), 0.0f);
    }
    p.far_plane = glm::vec4(far_local);
    const float largest = static_cast<float>(std::max(o.grid_width, o.grid_height));
    const float guard = o.guard_band == 0.0f ? 2.0f * largest : o.guard_band;
    s.bound = largest + guard;
    s.margin = std::ldexp(1.0f, -o.subpixel_bits) + kInfluenceFloatSlack * s.bound + o.extra_margin;
    s.half_size = 0.5f + s.margin;
    p.grid = glm::vec4(static_cast<float>(W), static_cast<float>(H), s.bound, s.margin);
    p.expansion = glm::vec4(s.half_size, detail::roundUpToFloat(1.0 + kInfluenceInflation + centre_shift), kInfluenceInflationPerUnit,
                            kInfluenceInsideRadius * kInfluenceInsideRadius);
    const double pi = 3.14159265358979323846;
    p.polygon = glm::vec4(detail::roundUpToFloat(1.0 / std::cos(pi / o.sides)), kInfluenceCutClearance,
                          kInfluenceCutClearancePerUnit, 0.0f);
    for (int j = 0; j < kInfluenceMaxSides; ++j) {
        const double angle = 2.0 * pi * j / o.sides;
        const float c = j < o.sides ? static_cast<float>(std::cos(angle)) : 0.0f;
        const float sn = j < o.sides ? static_cast<float>(std::sin(angle)) : 0.0f;
        p.directions[j / 2][(j & 1) * 2] = c;
        p.directions[j / 2][(j & 1) * 2 + 1] = sn;
    }
    p.config = glm::uvec4(static_cast<uint32_t>(o.sides), o.cut_by_supporting_plane ? PENUMBRA_INFLUENCE_CONFIG_CUT : 0u,
                          0u, 0u);
    s.max_vertices = PENUMBRA_INFLUENCE_MAX_VERTICES(o.sides);
    s.defines = {{"PENUMBRA_INFLUENCE_SIDES", std::to_string(o.sides)},
                 {"PENUMBRA_INFLUENCE_CUT", o.cut_by_supporting_plane ? "1" : "0"}};
    return s;
}

/// The CPU twin's result: what the geometry stage computes for one triangle.
struct InfluenceRegion {
    InfluenceRegionKind kind = InfluenceRegionKind::Dropped;
    uint32_t fallback = 0;  ///< PENUMBRA_INFLUENCE_FALLBACK_* bits (WholeGrid)
    int point_count = 0;    ///< the 3k far points (grid pixels), when all were computed
    std::array<glm::vec2, kInfluenceMaxPoints> points{};
    int polygon_count = 0;  ///< the undilated hull (after the cut), counter-clockwise
    std::array<glm::vec2, kInfluenceMaxPolygon> polygon{};
    int count = 0;          ///< the emitted polygon (dilated; WholeGrid: the grid), counter-clockwise
    std::array<glm::vec2, kInfluenceMaxVertices> pixels{};
};

namespace detail {

// Merges sorted a[0, na) and b[0, nb) into out (lexicographic (x, y)).
inline void influenceMerge(const glm::vec2* a, int na, const glm::vec2* b, int nb, glm::vec2* out) {
    int i = 0, j = 0, m = 0;
    while (i < na && j < nb) out[m++] = influenceLess(b[j], a[i]) ? b[j++] : a[i++];
    while (i < na) out[m++] = a[i++];
    while (j < nb) out[m++] = b[j++];
}

// One group (a convex polygon of k points in angular order, either orientation) in sorted order:
// split at the leftmost and rightmost points into two x-monotone chains and merge them.
inline void influenceSortGroup(const glm::vec2* g, int k, glm::vec2* out) {
    int left = 0, right = 0;
    for (int i = 1; i < k; ++i) {
        if (influenceLess(g[i], g[left])) left = i;
        if (influenceLess(g[right], g[i])) right = i;
    }
    glm::vec2 forward[kInfluenceMaxSides], backward[kInfluenceMaxSides];
    int nf = 0, nb = 0;
    for (int i = left;; i = (i + 1) % k) {  // left -> right, forwards
        forward[nf++] = g[i];
        if (i == right) break;
    }
    for (int i = (left + k - 1) % k; i != right; i = (i + k - 1) % k) backward[nb++] = g[i];  // left -> right, backwards (exclusive)
    influenceMerge(forward, nf, backward, nb, out);
}

// Andrew's monotone chain on sorted points; returns the counter-clockwise hull size.
inline int influenceMonotoneChain(const glm::vec2* s, int n, glm::vec2* hull) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
        while (m >= 2 && influenceCross2(hull[m - 1] - hull[m - 2], s[i] - hull[m - 2]) <= 0.0f) --m;
        hull[m++] = s[i];
    }
    const int lower = m + 1;
    for (int i = n - 2; i >= 0; --i) {
        while (m >= lower && influenceCross2(hull[m - 1] - hull[m - 2], s[i] - hull[m - 2]) <= 0.0f) --m;
        hull[m++] = s[i];
    }
    return m > 1 ? m - 1 : m;
}

// §4.1 dilation of a counter-clockwise convex polygon by [-h, h]^2 (see the header comment).
// Returns the vertex count, or -1 when the turn sequence is inconsistent.
inline int influenceDilate(const glm::vec2* poly, int n, float h, glm::vec2* out) {
    int count = 0, turns = 0;
    for (int i = 0; i < n; ++i) {
        const glm::vec2 q = poly[i];
        const glm::vec2 d_in = q - poly[(i + n - 1) % n];
        const glm::vec2 d_out = poly[(i + 1) % n] - q;
        const int k_in = conservativeEdgeCorner(d_in), k_out = conservativeEdgeCorner(d_out);
        const int steps = (k_out - k_in) & 3;
        turns += steps;
        if (steps == 3) return -1;
        const glm::vec2 c_in = h * conservativeCorner(k_in), c_out = h * conservativeCorner(k_out);
        const glm::vec2 a = q + c_in;
        if (steps == 0) {  // case i
            out[count++] = a;
            continue;
        }
        const glm::vec2 b = q + c_out;
        if (steps == 1) {  // case ii
            const float dot = mulRounded(d_in.x, d_out.x) + mulRounded(d_in.y, d_out.y);
            const float cross = influenceCross2(d_in, d_out);
            const float len2 = mulRounded(mulRounded(d_in.x, d_in.x) + mulRounded(d_in.y, d_in.y),
                                          mulRounded(d_out.x, d_out.x) + mulRounded(d_out.y, d_out.y));
            if (dot > 0.0f && cross > 0.0f && mulRounded(cross, cross) >= mulRounded(len2, 1.0f / 4096.0f)) {
                const float t = influenceCross2(c_out - c_in, d_out) / cross;
                out[count++] = glm::vec2(a.x + mulRounded(t, d_in.x), a.y + mulRounded(t, d_in.y));
            } else {
                out[count++] = a;
                out[count++] = b;
            }
            continue;
        }
        out[count++] = a;  // case iii: the three corners
        out[count++] = q + h * conservativeCorner((k_in + 1) & 3);
        out[count++] = b;
    }
    if (turns != 4) return -1;
    return count;
}

}  // namespace detail

/// CPU twin of penumbraInfluenceRegion: the same polygon, float, the same operations, for one
/// triangle with world-space (float) vertices.
inline InfluenceRegion influenceRegion(const glm::vec3& v0, const glm::vec3& v1, const glm::vec3& v2,
                                       const InfluenceRegionSetup& setup) {
    using namespace detail;
    InfluenceRegion out;
    const InfluenceRegionParams& p = setup.params;
    const glm::vec3 v[3] = {v0, v1, v2};
    for (int i = 0; i < 3; ++i) {
        if (nonFinite(v[i].x) || nonFinite(v[i].y) || nonFinite(v[i].z)) {
            out.kind = InfluenceRegionKind::Dropped;
            return out;
        }
    }
    const float W = p.grid.x, H = p.grid.y, B = p.grid.z, h = p.expansion.x;
    const glm::vec3 n_far(p.far_plane);
    glm::vec3 q[3];
    float s[3];
    int beyond = 0;
    for (int i = 0; i < 3; ++i) {
        const glm::vec3 d = v[i] - glm::vec3(p.center);
        q[i] = glm::vec3(influenceDot3(p.to_local[0], d), influenceDot3(p.to_local[1], d), influenceDot3(p.to_local[2], d));
        s[i] = influenceDot3(n_far, q[i]) + p.far_plane.w;
        if (!(s[i] < 0.0f)) ++beyond;
    }
    auto whole = [&](uint32_t flags) {
        out.kind = InfluenceRegionKind::WholeGrid;
        out.fallback = flags;
        out.count = 4;
        out.pixels[0] = glm::vec2(0.0f, 0.0f);
        out.pixels[1] = glm::vec2(W, 0.0f);
        out.pixels[2] = glm::vec2(W, H);
        out.pixels[3] = glm::vec2(0.0f, H);
        return out;
    };
    if (beyond == 3) {
        out.kind = InfluenceRegionKind::Culled;
        return out;
    }
    if (beyond > 0) return whole(PENUMBRA_INFLUENCE_FALLBACK_BEYOND_FAR);

    const int k = static_cast<int>(p.config.x);
    glm::vec2 groups[3][kInfluenceMaxSides];
    uint32_t flags = 0;
    for (int i = 0; i < 3 && flags == 0; ++i) {
        const glm::vec3 qi = q[i];
        const float r2 = influenceDot3(qi, qi);
        if (!(r2 > p.expansion.w)) {
            flags |= PENUMBRA_INFLUENCE_FALLBACK_INSIDE_LIGHT;
            break;
        }
        const float len = std::sqrt(r2);
        const float R = p.expansion.y + mulRounded(p.expansion.z, len);
        const float R2 = mulRounded(R, R);
        if (!(r2 > R2)) {
            flags |= PENUMBRA_INFLUENCE_FALLBACK_INSIDE_LIGHT;
            break;
        }
        const glm::vec3 C(influenceAffine(p.to_pixel[0], qi), influenceAffine(p.to_pixel[1], qi),
                          influenceAffine(p.to_pixel[2], qi));
        if (!(C.z > 0.0f) || !(std::abs(C.x) <= mulRounded(B, C.z)) || !(std::abs(C.y) <= mulRounded(B, C.z))) {
            flags |= PENUMBRA_INFLUENCE_FALLBACK_VERTEX;
            break;
        }
        // Silhouette circle of the ball of radius R seen from qi, and its circumscribed k-gon.
        const glm::vec3 m = influenceScale(qi, R2 / r2);
        const float rho = mulRounded(R, std::sqrt(r2 - R2)) / len;
        const float radius = mulRounded(rho, p.polygon.x);
        const glm::vec3 u = qi / len;
        const glm::vec3 au(std::abs(u.x), std::abs(u.y), std::abs(u.z));
        glm::vec3 a = au.x <= au.y && au.x <= au.z ? glm::vec3(0.0f, u.z, -u.y)
                      : au.y <= au.z              ? glm::vec3(-u.z, 0.0f, u.x)
                                                  : glm::vec3(u.y, -u.x, 0.0f);  // u x (the least aligned axis)
        a = a / std::sqrt(influenceDot3(a, a));
        const glm::vec3 b = influenceCross(u, a);
        for (int j = 0; j < k; ++j) {
            const glm::vec4 dir4 = p.directions[j / 2];
            const float cj = (j & 1) ? dir4.z : dir4.x, sj = (j & 1) ? dir4.w : dir4.y;
            const glm::vec3 g = m + (influenceScale(a, mulRounded(radius, cj)) + influenceScale(b, mulRounded(radius, sj)));
            const glm::vec3 dj = qi - g;
            const float aj = influenceDot3(n_far, dj);
            const glm::vec3 D(influenceDot3(p.to_pixel[0], dj), influenceDot3(p.to_pixel[1], dj),
                              influenceDot3(p.to_pixel[2], dj));
            if (!(aj > 0.0f) || !(D.z > 0.0f) || !(std::abs(D.x) <= mulRounded(B, D.z)) ||
                !(std::abs(D.y) <= mulRounded(B, D.z))) {
                flags |= PENUMBRA_INFLUENCE_FALLBACK_RAY;
                break;
            }
            const glm::vec3 P(mulRounded(aj, C.x) - mulRounded(s[i], D.x), mulRounded(aj, C.y) - mulRounded(s[i], D.y),
                              mulRounded(aj, C.z) - mulRounded(s[i], D.z));
            groups[i][j] = glm::vec2(P.x / P.z, P.y / P.z);
            out.points[static_cast<size_t>(i * k + j)] = groups[i][j];
        }
    }
    if (flags != 0) return whole(flags);
    out.point_count = 3 * k;

    // Hull: sort each group by chain merging, merge the groups, repair, monotone chain.
    glm::vec2 sorted_groups[3][kInfluenceMaxSides], ab[2 * kInfluenceMaxSides], all[kInfluenceMaxPoints];
    for (int i = 0; i < 3; ++i) influenceSortGroup(groups[i], k, sorted_groups[i]);
    influenceMerge(sorted_groups[0], k, sorted_groups[1], k, ab);
    influenceMerge(ab, 2 * k, sorted_groups[2], k, all);
    const int n_points = 3 * k;
    for (int i = 1; i < n_points; ++i) {  // insertion pass: a no-op when the merge was sorted
        const glm::vec2 x = all[i];
        int j = i - 1;
        while (j >= 0 && influenceLess(x, all[j])) {
            all[j + 1] = all[j];
            --j;
        }
        all[j + 1] = x;
    }
    glm::vec2 hull[2 * kInfluenceMaxPoints + 1];
    int n = influenceMonotoneChain(all, n_points, hull);

    // Optional cut by the supporting plane (sintorn2008 §4.3, [LLA06]).
    if ((p.config.y & PENUMBRA_INFLUENCE_CONFIG_CUT) != 0u && n >= 3) {
        const glm::vec3 e0 = q[1] - q[0], e1 = q[2] - q[0];
        const glm::vec3 nt = influenceCross(e0, e1);
        const float nn = influenceDot3(nt, nt);
        const float sliver = mulRounded(mulRounded(influenceDot3(e0, e0), influenceDot3(e1, e1)), 1.0f / 256.0f);
        const float dist = -influenceDot3(nt, q[0]);  // |nt| * signed distance of the light centre
        const float len0 = std::sqrt(influenceDot3(q[0], q[0]));
        const float clearance = p.polygon.y + mulRounded(p.polygon.z, len0);
        if (nn > 0.0f && nn >= sliver && mulRounded(dist, dist) > mulRounded(mulRounded(clearance, clearance), nn)) {
            const glm::vec3 nk = dist > 0.0f ? -nt : nt;  // keep rays with dot(nk, d) > 0
            const glm::vec3 line(influenceDot3(p.cut_lines[0], nk), influenceDot3(p.cut_lines[1], nk),
                                 influenceDot3(p.cut_lines[2], nk));
            const float slack = mulRounded(p.grid.w, std::abs(line.x) + std::abs(line.y));
            glm::vec2 clipped[kInfluenceMaxPolygon];
            int m = 0;
            glm::vec2 prev = hull[n - 1];
            float d_prev = (mulRounded(line.x, prev.x) + mulRounded(line.y, prev.y)) + line.z + slack;
            for (int i = 0; i < n; ++i) {
                const glm::vec2 cur = hull[i];
                const float d_cur = (mulRounded(line.x, cur.x) + mulRounded(line.y, cur.y)) + line.z + slack;
                if (d_cur >= 0.0f) {
                    if (d_prev < 0.0f) {
                        const float t = d_cur / (d_cur - d_prev);
                        clipped[m++] = glm::vec2(cur.x + mulRounded(t, prev.x - cur.x), cur.y + mulRounded(t, prev.y - cur.y));
                    }
                    clipped[m++] = cur;
                } else if (d_prev >= 0.0f) {
                    const float t = d_prev / (d_prev - d_cur);
                    clipped[m++] = glm::vec2(prev.x + mulRounded(t, cur.x - prev.x), prev.y + mulRounded(t, cur.y - prev.y));
                }
                prev = cur;
                d_prev = d_cur;
            }
            if (m == 0) {
                out.kind = InfluenceRegionKind::Culled;
                return out;
            }
            n = m;
            for (int i = 0; i < n; ++i) hull[i] = clipped[i];
        }
    }
    out.polygon_count = n;
    for (int i = 0; i < n; ++i) out.polygon[static_cast<size_t>(i)] = hull[i];

    glm::vec2 lo = hull[0], hi = hull[0];
    for (int i = 1; i < n; ++i) {
        lo = glm::min(lo, hull[i]);
        hi = glm::max(hi, hull[i]);
    }
    lo -= glm::vec2(h);
    hi += glm::vec2(h);
    if (lo.x > W || lo.y > H || hi.x < 0.0f || hi.y < 0.0f) {
        out.kind = InfluenceRegionKind::Culled;
        return out;
    }
    int count = n >= 3 ? influenceDilate(hull, n, h, out.pixels.data()) : -1;
    out.kind = InfluenceRegionKind::Hull;
    if (count < 0) {
        out.pixels[0] = lo;
        out.pixels[1] = glm::vec2(hi.x, lo.y);
        out.pixels[2] = hi;
        out.pixels[3] = glm::vec2(lo.x, hi.y);
        count = 4;
        out.kind = InfluenceRegionKind::Box;
    }
    PENUMBRA_ASSERT(count <= setup.max_vertices);
    out.count = count;
    return out;
}

/// The texels GL's rule predicts for the emitted polygon (centre strictly inside, or on a top or
/// left edge), in double on the float vertices; texels whose centre lies within `tolerance` of the
/// boundary go to `uncertain` (a rasterizer that snaps vertices may decide them either way).
inline HullRaster influenceRegionTexels(const InfluenceRegion& region, const InfluenceRegionSetup& setup,
                                        double tolerance = 0.0) {
    return detail::pixelRule(region.pixels.data(), region.count, setup.width(), setup.height(), nullptr, tolerance);
}

/// The coverage rule of the soft pipeline's coverage pass (SampleBasedSoftGpuOptions::
/// coverage_texels; its GLSL twin penumbraSbsCoverageSpan in
/// shaders/penumbra/sample_based_soft/light_pass_coverage.comp.glsl, the same double operations):
/// texel (x, y) is visited when its centre lies within kInfluenceCoverageSlack of the polygon in x
/// and in y (the polygon grown by that square; on row y, the extent of the edges' points within the
/// slack of y + 0.5, grown by the slack). So it holds every texel whose centre lies inside the
/// polygon or within the slack of it: GL's rule, for any rasterizer that snaps vertices to 1/128
/// pixel or finer (tests/influence_region_test.cpp).
inline constexpr double kInfluenceCoverageSlack = 1.0 / 64.0;

/// [first, last] of the texels whose centre lies within the slack of [lo, hi] on an axis of `size`
/// texels (first > last: none).
inline glm::ivec2 influenceCoverageRange(double lo, double hi, int size) {
    const double first = std::ceil(std::clamp(lo - kInfluenceCoverageSlack - 0.5, -1.0, double(size)));
    const double last = std::floor(std::clamp(hi + kInfluenceCoverageSlack - 0.5, -1.0, double(size)));
    return {std::max(0, static_cast<int>(first)), std::min(size - 1, static_cast<int>(last))};
}

/// Row y's texels [x0, x1] of the polygon `pixels[0, count)` under the coverage rule.
inline glm::ivec2 influenceCoverageSpan(const glm::vec2* pixels, int count, int y, int width) {
    const double yc = double(y) + 0.5;
    double left = 1e300, right = -1e300;
    for (int j = 0; j < count; ++j) {
        const glm::dvec2 a(pixels[j]), b(pixels[j + 1 < count ? j + 1 : 0]);
        const double bottom = std::min(a.y, b.y), top = std::max(a.y, b.y);
        if (yc < bottom - kInfluenceCoverageSlack || yc > top + kInfluenceCoverageSlack) continue;
        if (top > bottom) {
            const double t0 = std::clamp((yc - kInfluenceCoverageSlack - a.y) / (b.y - a.y), 0.0, 1.0);
            const double t1 = std::clamp((yc + kInfluenceCoverageSlack - a.y) / (b.y - a.y), 0.0, 1.0);
            const double x0 = a.x + t0 * (b.x - a.x), x1 = a.x + t1 * (b.x - a.x);
            left = std::min(left, std::min(x0, x1));
            right = std::max(right, std::max(x0, x1));
        } else {
            left = std::min(left, std::min(a.x, b.x));
            right = std::max(right, std::max(a.x, b.x));
        }
    }
    return influenceCoverageRange(left, right, width);
}

/// Every texel the coverage rule visits for the emitted polygon, row by row.
inline std::vector<glm::ivec2> influenceCoverageTexels(const InfluenceRegion& region, const InfluenceRegionSetup& setup) {
    std::vector<glm::ivec2> out;
    if (region.count <= 0) return out;
    double lo = 1e300, hi = -1e300;
    for (int j = 0; j < region.count; ++j) {
        lo = std::min(lo, double(region.pixels[size_t(j)].y));
        hi = std::max(hi, double(region.pixels[size_t(j)].y));
    }
    const glm::ivec2 rows = influenceCoverageRange(lo, hi, setup.height());
    for (int y = rows.x; y <= rows.y; ++y) {
        const glm::ivec2 span = influenceCoverageSpan(region.pixels.data(), region.count, y, setup.width());
        for (int x = span.x; x <= span.y; ++x) out.emplace_back(x, y);
    }
    return out;
}

/// GL's rule for one texel of the emitted polygon (double, on the float vertices' convex hull:
/// detail::convexPixelHull says why).
inline bool influenceRegionCoversTexel(const InfluenceRegion& region, int x, int y) {
    const std::vector<glm::dvec2> hull = detail::convexPixelHull(region.pixels.data(), region.count);
    if (hull.size() < 3) return false;
    const glm::dvec2 centre(x + 0.5, y + 0.5);
    for (size_t i = 0; i < hull.size(); ++i) {
        const glm::dvec2 a = hull[i];
        const glm::dvec2 b = hull[(i + 1) % hull.size()];
        const glm::dvec2 d = b - a;
        if (d.x == 0.0 && d.y == 0.0) continue;
        const double outside = d.y * (centre.x - a.x) - d.x * (centre.y - a.y);  // > 0: outside (CCW)
        const bool top_left = (d.y == 0.0 && d.x < 0.0) || d.y < 0.0;
        if (outside > 0.0 || (outside == 0.0 && !top_left)) return false;
    }
    return true;
}

namespace detail {

inline double influenceSegment2(const glm::dvec3& a, const glm::dvec3& b) {  // |closest point of [a, b] to 0|^2
    const glm::dvec3 e = b - a;
    const double ee = glm::dot(e, e);
    const double t = ee > 0.0 ? std::clamp(-glm::dot(a, e) / ee, 0.0, 1.0) : 0.0;
    const glm::dvec3 x = a + t * e;
    return glm::dot(x, x);
}

inline double influenceRay2(const glm::dvec3& a, const glm::dvec3& e) {  // ray a + t e, t >= 0
    const double ee = glm::dot(e, e);
    const double t = ee > 0.0 ? std::max(0.0, -glm::dot(a, e) / ee) : 0.0;
    const glm::dvec3 x = a + t * e;
    return glm::dot(x, x);
}

// Squared distance from 0 to the wedge {p + s ((1 - u) a + u b - p): s >= 1, u in [0, 1]}.
inline double influenceWedge2(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b) {
    const glm::dvec3 ea = a - p, eb = b - p;
    const double g11 = glm::dot(ea, ea), g12 = glm::dot(ea, eb), g22 = glm::dot(eb, eb);
    const double det = g11 * g22 - g12 * g12;
    double best = std::min(influenceSegment2(a, b), std::min(influenceRay2(a, ea), influenceRay2(b, eb)));
    if (det > 1e-24 * g11 * g22) {
        const double r1 = -glm::dot(p, ea), r2 = -glm::dot(p, eb);
        const double alpha = (r1 * g22 - r2 * g12) / det, beta = (r2 * g11 - r1 * g12) / det;
        if (alpha >= 0.0 && beta >= 0.0 && alpha + beta >= 1.0) {
            const glm::dvec3 x = p + alpha * ea + beta * eb;
            best = std::min(best, glm::dot(x, x));
        }
    }
    return best;
}

inline double influenceOrient(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& d) {
    return glm::dot(glm::cross(b - a, c - a), d - a);
}

// Does the segment [p, q] meet the closed triangle (a, b, c)? (Signed volumes; a segment in the
// triangle's plane counts as missing here: the boundary distances decide those.)
inline bool influenceSegmentHits(const glm::dvec3& p, const glm::dvec3& q, const glm::dvec3& a, const glm::dvec3& b,
                                 const glm::dvec3& c) {
    const double sp = influenceOrient(a, b, c, p), sq = influenceOrient(a, b, c, q);
    if ((sp > 0.0 && sq > 0.0) || (sp < 0.0 && sq < 0.0) || (sp == 0.0 && sq == 0.0)) return false;
    const double e0 = influenceOrient(p, q, a, b), e1 = influenceOrient(p, q, b, c), e2 = influenceOrient(p, q, c, a);
    return (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) || (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0);
}

}  // namespace detail

/// The exact predicate (double): is receiver p shadowed by the closed triangle (a, b, c) from SOME
/// point of the light's bounding ball (the light itself for Sphere and Ellipsoid; a superset of a
/// Disk's or Rectangle's shadow)? Closest approach: p is shadowed from y iff y lies in
/// K = {p + s (x - p): x in T, s >= 1}, a convex truncated cone, so in the light's
/// normalised space (the ball is the unit ball) p is shadowed iff dist(0, K) <= 1: zero when the
/// centre itself lies in K (the segment from p to the centre meets T), else the distance to K's
/// boundary, T and the three wedges beyond T's edges (the lateral faces of the truncated cone).
inline bool influenceShadowedContinuous(const LightFrame& frame, const glm::dvec3& a, const glm::dvec3& b,
                                        const glm::dvec3& c, const glm::dvec3& p, double* distance = nullptr) {
    const glm::dvec3 la = frame.toLocal(a), lb = frame.toLocal(b), lc = frame.toLocal(c), lp = frame.toLocal(p);
    if (detail::influenceSegmentHits(lp, glm::dvec3(0.0), la, lb, lc)) {
        if (distance) *distance = 0.0;
        return true;
    }
    double best = detail::pointTriangleDistance2(glm::dvec3(0.0), la, lb, lc);
    best = std::min(best, detail::influenceWedge2(lp, la, lb));
    best = std::min(best, detail::influenceWedge2(lp, lb, lc));
    best = std::min(best, detail::influenceWedge2(lp, lc, la));
    if (distance) *distance = std::sqrt(best);
    return best <= 1.0;
}

/// Grid-pixel position (double) of a world point under the setup's projection; w <= 0: behind.
inline glm::dvec3 influenceProjectPixel(const InfluenceRegionSetup& setup, const glm::dvec3& world) {
    const glm::dvec3 q = setup.frame.toLocal(world);
    const glm::dvec4 clip = setup.local_to_clip * glm::dvec4(q, 1.0);
    return glm::dvec3((clip.x / clip.w * 0.5 + 0.5) * setup.width(), (clip.y / clip.w * 0.5 + 0.5) * setup.height(), clip.w);
}

}  // namespace penumbra

#endif
