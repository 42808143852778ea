// Influence regions (penumbra/influence_region.hpp, sintorn2008 §4.1): the CPU twin never misses a
// shadowed texel (random + adversarial (triangle, light, far plane) cases against the exact
// continuous-light predicate, cross-checked with the segment oracle on light samples), its
// tightness per k, the setup's bad-input errors, and the fallbacks.
#include <penumbra/influence_region.hpp>
#include <penumbra/light_samples.hpp>
#include <penumbra/pipelines/alias_free_hard.hpp>
#include <penumbra/reference/visibility.hpp>
#include <penumbra/sample_lists.hpp>

#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <set>
#include <string>
#include <vector>

namespace {

using penumbra::InfluenceRegion;
using penumbra::InfluenceRegionKind;
using penumbra::InfluenceRegionSetup;
using penumbra::Light;
using penumbra::LightShape;

struct Rng {
    std::mt19937_64 engine;
    explicit Rng(uint64_t seed) : engine(seed) {}
    double uniform(double lo = 0.0, double hi = 1.0) {
        return lo + (hi - lo) * (static_cast<double>(engine() >> 11) * (1.0 / 9007199254740992.0));
    }
    int below(int n) { return static_cast<int>(engine() % static_cast<uint64_t>(n)); }
    glm::dvec3 sphere() {
        for (;;) {
            const glm::dvec3 v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
            const double l = glm::length(v);
            if (l > 1e-3 && l <= 1.0) return v / l;
        }
    }
};

// Rounded to float (the light centre the GPU sees is a float). Through the bits: GCC -O3 once
// folded the double -> float -> double round trip of a glm conversion here.
glm::dvec3 toF(const glm::dvec3& v) {
    return glm::dvec3(penumbra::detail::opaque(static_cast<float>(v.x)), penumbra::detail::opaque(static_cast<float>(v.y)),
                      penumbra::detail::opaque(static_cast<float>(v.z)));
}

// The light grid's pixel-homogeneous rows (double) from the setup's local_to_clip.
glm::dmat3 pixelLinear(const InfluenceRegionSetup& s) {
    glm::dmat3 m;
    for (int c = 0; c < 3; ++c) {
        const glm::dvec4& col = s.local_to_clip[c];
        m[c][0] = 0.5 * s.width() * (col[0] + col[3]);
        m[c][1] = 0.5 * s.height() * (col[1] + col[3]);
        m[c][2] = col[3];
    }
    return m;
}

// Local point on the texel ray through grid pixel (x, y) at light depth `depth` (clip.w).
glm::dvec3 rayPoint(const InfluenceRegionSetup& s, const glm::dmat3& inv_linear, double x, double y, double depth) {
    const glm::dvec3 d = inv_linear * glm::dvec3(x, y, 1.0);
    const glm::dvec3 row_w(s.local_to_clip[0][3], s.local_to_clip[1][3], s.local_to_clip[2][3]);
    return s.projection_center_local + d * (depth / glm::dot(row_w, d));
}

double farSide(const InfluenceRegionSetup& s, const glm::dvec3& local) {
    return glm::dot(glm::dvec3(s.far_plane_local), local) + s.far_plane_local.w;
}

struct Scenario {
    Light light;
    glm::mat4 vp;
    InfluenceRegionSetup setup;
    double depth_max = 0.0;  // light depth of the far plane along the axis (perpendicular planes)
};

// A random light over a receiver box, its grid, and a far plane (perpendicular or a floor).
Scenario makeScenario(Rng& rng, int sides, bool cut) {
    Scenario sc;
    const double scale = rng.below(2) ? 1.0 : 10.0;
    const double offsets[4] = {0.0, 0.0, 1e3, 3e4};
    const glm::dvec3 origin(offsets[rng.below(4)], 0.5 * offsets[rng.below(4)], -offsets[rng.below(4)]);
    const double height = rng.uniform(5.0, 12.0) * scale;
    const double radius = rng.uniform(0.02, 1.0) * scale;
    Light& l = sc.light;
    const int shape = rng.below(8);
    l.shape = shape < 4 ? LightShape::Sphere : shape < 6 ? LightShape::Ellipsoid : shape < 7 ? LightShape::Disk
                                                                                            : LightShape::Rectangle;
    l.center = toF(origin + glm::dvec3(rng.uniform(-1, 1) * scale, height, rng.uniform(-1, 1) * scale));
    l.axis_z = rng.sphere();
    l.axis_x = rng.sphere();
    if (std::abs(glm::dot(l.axis_x, l.axis_z)) > 0.9) l.axis_x = glm::cross(l.axis_z, glm::dvec3(0.3, 0.5, 0.8));
    l.size = glm::dvec3(radius, radius * rng.uniform(0.3, 1.0), radius * rng.uniform(0.3, 1.0));
    const glm::vec3 lo(origin + glm::dvec3(-5, 0, -5) * scale), hi(origin + glm::dvec3(5, 1, 5) * scale);
    sc.vp = penumbra::lightViewProjectionForBounds(glm::vec4(glm::vec3(l.center), 1.0f), lo, hi);
    penumbra::InfluenceRegionOptions o;
    const int sizes[5] = {32, 100, 256, 1024, 2048};
    o.grid_width = sizes[rng.below(5)];
    o.grid_height = rng.below(3) ? o.grid_width : sizes[rng.below(5)];
    o.sides = sides;
    o.cut_by_supporting_plane = cut;
    double depth = 0.0;
    for (int k = 0; k < 8; ++k) {
        const glm::dvec4 corner((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z, 1.0);
        depth = std::max(depth, (glm::dmat4(sc.vp) * corner).w);
    }
    if (rng.below(10) < 7) {
        sc.depth_max = depth * rng.uniform(1.0, 1.3);
        o.far_plane = penumbra::influenceFarPlaneAtDepth(sc.vp, sc.depth_max);
    } else {  // a (slightly tilted) floor below the box
        const glm::dvec3 n = glm::normalize(glm::dvec3(rng.uniform(-0.1, 0.1), 1.0, rng.uniform(-0.1, 0.1)));
        const glm::dvec3 at = origin - glm::dvec3(0, rng.uniform(0.0, 0.5) * scale, 0);
        o.far_plane = glm::dvec4(n, -glm::dot(n, at));
        sc.depth_max = depth * 2.0;
    }
    sc.setup = penumbra::influenceRegionSetup(l, sc.vp, o);
    return sc;
}

// A caster triangle (world, float) of one of the adversarial families.
void makeTriangle(Rng& rng, const Scenario& sc, const glm::dmat3& inv_linear, int family, glm::vec3 (&tri)[3]) {
    const InfluenceRegionSetup& s = sc.setup;
    const penumbra::LightFrame& f = s.frame;
    const double W = s.width(), H = s.height();
    auto frustum = [&](double depth_lo, double depth_hi) {
        const double x = rng.uniform(-0.3, 1.3) * W, y = rng.uniform(-0.3, 1.3) * H;
        const double depth = rng.uniform(depth_lo, depth_hi);
        return f.toWorld(rayPoint(s, inv_linear, x, y, depth));
    };
    const glm::dvec3 c = f.center;
    const double r = f.scale.x;  // a length scale of the light
    const double dist_light = glm::length(f.toWorld(rayPoint(s, inv_linear, 0.5 * W, 0.5 * H, sc.depth_max)) - c);
    glm::dvec3 v[3];
    switch (family) {
        case 0:
        default: {  // random, between the light and the far plane, small to large
            const glm::dvec3 base = frustum(0.05 * sc.depth_max, 0.95 * sc.depth_max);
            const double size = dist_light * std::pow(10.0, rng.uniform(-3.0, -0.5));
            v[0] = base;
            v[1] = base + size * rng.sphere();
            v[2] = base + size * rng.sphere();
            break;
        }
        case 1: {  // sliver: nearly collinear
            const glm::dvec3 base = frustum(0.05 * sc.depth_max, 0.9 * sc.depth_max);
            const glm::dvec3 e = dist_light * 0.05 * rng.sphere();
            v[0] = base;
            v[1] = base + e;
            v[2] = base + rng.uniform(-0.5, 1.5) * e + dist_light * 1e-7 * rng.sphere();
            break;
        }
        case 2: {  // degenerate: repeated vertices
            const glm::dvec3 base = frustum(0.05 * sc.depth_max, 0.9 * sc.depth_max);
            v[0] = v[1] = base;
            v[2] = rng.below(2) ? base : base + dist_light * 0.01 * rng.sphere();
            break;
        }
        case 3: {  // near the light: 1.0 .. 2 light radii from its centre, towards the grid
            for (auto& x : v) {
                glm::dvec3 q = rng.sphere();
                const glm::dvec3 axis = glm::normalize(glm::dvec3(s.far_plane_local));
                if (glm::dot(q, axis) < 0.0) q = q - 2.0 * glm::dot(q, axis) * axis;
                x = f.toWorld(q * rng.uniform(1.0, 2.0));
            }
            break;
        }
        case 4: {  // grazing the far plane, possibly straddling it
            const glm::dvec3 base = frustum(0.97 * sc.depth_max, 0.999 * sc.depth_max);
            const double size = dist_light * 0.02;
            v[0] = base;
            v[1] = base + size * rng.sphere();
            v[2] = base + size * rng.sphere();
            break;
        }
        case 5: {  // large, spanning much of the frustum
            for (auto& x : v) x = frustum(0.2 * sc.depth_max, 0.8 * sc.depth_max);
            break;
        }
        case 6: {  // close to the light but outside it: 2 .. 10 radii, small
            glm::dvec3 q = rng.sphere();
            const glm::dvec3 axis = glm::normalize(glm::dvec3(s.far_plane_local));
            if (glm::dot(q, axis) < 0.3) q = glm::normalize(q + axis);
            const glm::dvec3 base = f.toWorld(q * rng.uniform(2.0, 10.0));
            v[0] = base;
            v[1] = base + r * 0.5 * rng.sphere();
            v[2] = base + r * 0.5 * rng.sphere();
            break;
        }
    }
    for (int i = 0; i < 3; ++i) tri[i] = glm::vec3(v[i]);
}

// Signed distance (px) of point x outside the convex CCW polygon (<= 0 inside).
double outsideDistance(const InfluenceRegion& r, const glm::dvec2& x) {
    double worst = -1e300;
    for (int i = 0; i < r.polygon_count; ++i) {
        const glm::dvec2 a(r.polygon[static_cast<size_t>(i)]), b(r.polygon[static_cast<size_t>((i + 1) % r.polygon_count)]);
        const glm::dvec2 d = b - a;
        const double l = glm::length(d);
        if (l == 0.0) continue;
        worst = std::max(worst, (d.y * (x.x - a.x) - d.x * (x.y - a.y)) / l);
    }
    return worst;
}

struct Stats {
    long cases = 0, points = 0, shadowed = 0, misses = 0, float_texel_misses = 0;
    long kinds[5] = {0, 0, 0, 0, 0};
    long fallback_bits[4] = {0, 0, 0, 0};
    long families[7] = {0, 0, 0, 0, 0, 0, 0};
    double max_excursion = -1e300;  // px outside the undilated polygon, over shadowed points
    long sample_checks = 0, sample_inconsistent = 0;
    // The soft pipeline's coverage pass (influenceCoverageSpan): shadowed receivers outside it, and
    // texels GL's rule (or a rasterizer snapping to 1/128 px) covers that it does not visit.
    long coverage_misses = 0, coverage_gl_misses = 0, coverage_checked = 0;
    double coverage_texels = 0.0, gl_texels = 0.0;
};

void runCases(long count, uint64_t seed, Stats& st) {
    Rng rng(seed);
    const int sides_list[4] = {4, 6, 8, 12};
    for (long n = 0; n < count; ++n) {
        const int sides = sides_list[n % 4];
        const bool cut = (n / 4) % 2 == 1;
        const Scenario sc = makeScenario(rng, sides, cut);
        const InfluenceRegionSetup& s = sc.setup;
        const glm::dmat3 inv_linear = glm::inverse(pixelLinear(s));
        const int family = rng.below(10) < 4 ? 0 : rng.below(7);
        glm::vec3 tri[3];
        makeTriangle(rng, sc, inv_linear, family, tri);
        ++st.families[family];
        const InfluenceRegion region = penumbra::influenceRegion(tri[0], tri[1], tri[2], s);
        ++st.cases;
        ++st.kinds[static_cast<int>(region.kind)];
        for (int b = 0; b < 4; ++b) st.fallback_bits[b] += (region.fallback >> b) & 1u;
        const glm::dvec3 a(tri[0]), b(tri[1]), c(tri[2]);
        const penumbra::LightFrame& f = s.frame;
        // The oracle's light: the true one (identical here: the test's light centres are floats).
        const penumbra::LightFrame tf = penumbra::lightFrame(sc.light);
        const glm::dvec3 la = f.toLocal(a), lb = f.toLocal(b), lc = f.toLocal(c);
        const double s_eye = farSide(s, s.projection_center_local);
        const bool near_origin = glm::length(f.center) < 1000.0;
        const glm::mat4 texture = penumbra::lightTextureMatrix(sc.vp, penumbra::LightDepthRange::Unclipped);
        auto check = [&](const glm::dvec3& world) {
            const glm::dvec3 local = f.toLocal(world);
            const double side = farSide(s, local);
            if (!(side <= 0.0 && side > s_eye)) return;
            const glm::dvec3 pix = penumbra::influenceProjectPixel(s, world);
            if (!(pix.z > 0.0) || !(pix.x >= 0.0 && pix.x < s.width() && pix.y >= 0.0 && pix.y < s.height())) return;
            ++st.points;
            if (!penumbra::influenceShadowedContinuous(tf, a, b, c, world)) return;
            ++st.shadowed;
            if (region.kind == InfluenceRegionKind::Dropped) return;  // NaN input only: nothing promised
            const int x = static_cast<int>(std::floor(pix.x)), y = static_cast<int>(std::floor(pix.y));
            if (region.count > 0) {
                const glm::ivec2 span = penumbra::influenceCoverageSpan(region.pixels.data(), region.count, y, s.width());
                if (x < span.x || x > span.y) {
                    if (++st.coverage_misses <= 5)
                        MESSAGE("coverage miss: case ", n, " family ", family, " texel (", x, ", ", y, ") span [", span.x, ", ", span.y, "]");
                }
            }
            if (!penumbra::influenceRegionCoversTexel(region, x, y)) {
                if (++st.misses <= 5) {
                    MESSAGE("miss: case ", n, " family ", family, " k ", sides, " cut ", cut, " kind ",
                            penumbra::influenceRegionKindName(region.kind), " texel (", x, ", ", y, ") grid ", s.width(),
                            "x", s.height(), " pixel (", pix.x, ", ", pix.y, ")");
                }
            }
            // The texel a float sample-list build would file it under (lightTextureMatrix, float).
            const glm::vec3 wf(world);
            const glm::vec4 t = penumbra::detail::transformPoint(texture, wf.x, wf.y, wf.z);
            // Only near the origin: far from it a float world-space transform is not how lists are
            // built (docs/design.md: light- or camera-relative coordinates there).
            if (near_origin && t.w > 0.0f && t.x >= 0.0f && t.x <= t.w && t.y >= 0.0f && t.y <= t.w) {
                const int fx = std::min(static_cast<int>(std::floor((t.x / t.w) * static_cast<float>(s.width()))), s.width() - 1);
                const int fy = std::min(static_cast<int>(std::floor((t.y / t.w) * static_cast<float>(s.height()))), s.height() - 1);
                if (penumbra::influenceShadowedContinuous(tf, a, b, c, glm::dvec3(wf)) &&
                    !penumbra::influenceRegionCoversTexel(region, fx, fy)) {
                    ++st.float_texel_misses;
                }
            }
            if (region.kind == InfluenceRegionKind::Hull && region.polygon_count >= 3) {
                const double ex = outsideDistance(region, glm::dvec2(pix));
                if (ex > st.max_excursion && ex > 0.01) {  // report the worst ones (a diagnostic, not a miss)
                    MESSAGE("excursion ", ex, " px: case ", n, " family ", family, " k ", sides, " cut ", cut, " shape ",
                            int(sc.light.shape), " grid ", s.width(), "x", s.height(), " polygon ", region.polygon_count);
                }
                st.max_excursion = std::max(st.max_excursion, ex);
            }
        };
        // The coverage rule against GL's, every 4th case whose region's box holds at most 2^14
        // texels (the pass takes boxes of at most coverage_texels, 4096 by default): every texel
        // GL's rule covers, or leaves within 1/128 px of the boundary (a snapping rasterizer's
        // choice), is visited.
        double box_area = 0.0;
        if (region.count > 0) {
            glm::dvec2 lo(1e300), hi(-1e300);
            for (int j = 0; j < region.count; ++j) {
                lo = glm::min(lo, glm::dvec2(region.pixels[size_t(j)]));
                hi = glm::max(hi, glm::dvec2(region.pixels[size_t(j)]));
            }
            lo = glm::max(lo, glm::dvec2(0.0));
            hi = glm::min(hi, glm::dvec2(s.width(), s.height()));
            box_area = (hi.x - lo.x + 2.0) * (hi.y - lo.y + 2.0);
        }
        if (n % 4 == 0 && region.count > 0 && box_area <= 16384.0) {
            // GL's texels, and the texels whose centre lies within 1/128 px of the polygon's
            // float hull (its segments), where a snapping rasterizer may go either way.
            penumbra::HullRaster gl = penumbra::influenceRegionTexels(region, s);
            gl.uncertain.clear();
            const std::vector<glm::dvec2> hull = penumbra::detail::convexPixelHull(region.pixels.data(), region.count);
            glm::dvec2 blo(1e300), bhi(-1e300);
            for (const glm::dvec2& v : hull) {
                blo = glm::min(blo, v);
                bhi = glm::max(bhi, v);
            }
            for (int y = std::max(0, int(std::floor(blo.y - 1.0))); y <= std::min(s.height() - 1, int(std::ceil(bhi.y + 1.0))); ++y)
                for (int x = std::max(0, int(std::floor(blo.x - 1.0))); x <= std::min(s.width() - 1, int(std::ceil(bhi.x + 1.0))); ++x) {
                    const glm::dvec2 c(x + 0.5, y + 0.5);
                    double nearest = 1e300;
                    for (size_t i = 0; i < hull.size(); ++i) {
                        const glm::dvec2 a = hull[i], d = hull[(i + 1) % hull.size()] - a;
                        const double dd = glm::dot(d, d);
                        const double t = dd > 0.0 ? std::clamp(glm::dot(c - a, d) / dd, 0.0, 1.0) : 0.0;
                        nearest = std::min(nearest, glm::length(c - (a + t * d)));
                    }
                    if (nearest <= 1.0 / 128.0) gl.uncertain.emplace_back(x, y);
                }
            const std::vector<glm::ivec2> visited = penumbra::influenceCoverageTexels(region, s);
            std::set<std::pair<int, int>> set;
            for (const glm::ivec2& t : visited) set.emplace(t.x, t.y);
            ++st.coverage_checked;
            st.coverage_texels += double(visited.size());
            st.gl_texels += double(gl.fragments.size());
            for (const auto* list : {&gl.fragments, &gl.uncertain})
                for (const glm::ivec2& t : *list)
                    if (!set.count({t.x, t.y}) && ++st.coverage_gl_misses <= 5)
                        MESSAGE("coverage misses GL's texel (", t.x, ", ", t.y, "): case ", n, " family ", family);
        }
        // Boundary-ish shadowed points: y on the light's bounding sphere, x on the triangle
        // (edge, vertex or interior), p = y + s (x - y) up to the far plane.
        for (int i = 0; i < 24; ++i) {
            const glm::dvec3 y = rng.sphere();
            const double u = rng.uniform(), w = rng.uniform();
            glm::dvec3 x;
            const int where = rng.below(4);
            if (where == 0) x = (rng.below(3) == 0 ? la : rng.below(2) ? lb : lc);
            else if (where < 3) {
                const int e = rng.below(3);
                const glm::dvec3 p0 = e == 0 ? la : e == 1 ? lb : lc, p1 = e == 0 ? lb : e == 1 ? lc : la;
                x = p0 + u * (p1 - p0);
            } else {
                const double su = std::sqrt(u);
                x = (1 - su) * la + su * (1 - w) * lb + su * w * lc;
            }
            const double sy = farSide(s, y), sx = farSide(s, x);
            double smax = 64.0;
            if (sx > sy) smax = std::min(smax, -sy / (sx - sy));
            if (!(smax >= 1.0)) continue;
            const double t = rng.below(4) == 0 ? smax : 1.0 + (smax - 1.0) * rng.uniform();
            check(f.toWorld(y + t * (x - y)));
        }
        // Random receivers in the frustum.
        for (int i = 0; i < 24; ++i) {
            const double depth = rng.uniform(0.02, 1.0) * sc.depth_max;
            check(f.toWorld(rayPoint(s, inv_linear, rng.uniform() * s.width(), rng.uniform() * s.height(), depth)));
        }
        // Every 64th case: the segment oracle on light samples never finds a shadow the continuous
        // predicate misses (it is a superset: sampled light points lie in the light).
        if (n % 64 == 0) {
            penumbra::LightSampleOptions so;
            so.count = 64;
            so.sets = 1;
            const penumbra::LightSampleSets samples = penumbra::makeLightSampleSets(sc.light, so);
            const std::vector<glm::dvec3> vertices = {a, b, c};
            const std::vector<uint32_t> indices = {0, 1, 2};
            if (!penumbra::detail::degenerateTriangle(a, b, c)) {
                const penumbra::reference::VisibilityOracle oracle(vertices, indices);
                for (int i = 0; i < 16; ++i) {
                    const double depth = rng.uniform(0.05, 1.0) * sc.depth_max;
                    const glm::dvec3 p = f.toWorld(rayPoint(s, inv_linear, rng.uniform() * s.width(), rng.uniform() * s.height(), depth));
                    bool any = false;
                    for (const glm::dvec3& y : samples.world) any = any || oracle.segmentBlocked(p, y);
                    ++st.sample_checks;
                    if (any && !penumbra::influenceShadowedContinuous(tf, a, b, c, p)) ++st.sample_inconsistent;
                }
            }
        }
    }
}

void report(const Stats& st, const char* what) {
    MESSAGE(std::string(what), ": ", st.cases, " cases (families random/sliver/degenerate/near-light/grazing-far/large/close: ",
            st.families[0], "/", st.families[1], "/", st.families[2], "/", st.families[3], "/", st.families[4], "/",
            st.families[5], "/", st.families[6], "), ", st.points, " receivers in the grid, ", st.shadowed,
            " shadowed, misses ", st.misses, " (float-texel misses ", st.float_texel_misses, "); kinds dropped/culled/hull/box/whole: ",
            st.kinds[0], "/", st.kinds[1], "/", st.kinds[2], "/", st.kinds[3], "/", st.kinds[4],
            "; whole-grid reasons beyond-far/inside-light/vertex/ray: ", st.fallback_bits[0], "/", st.fallback_bits[1], "/",
            st.fallback_bits[2], "/", st.fallback_bits[3], "; max excursion of a shadowed receiver outside the float hull ",
            st.max_excursion, " px; sampled-oracle checks ", st.sample_checks, ", inconsistent ", st.sample_inconsistent,
            "; coverage rule: misses ", st.coverage_misses, ", GL texels not visited ", st.coverage_gl_misses, " over ",
            st.coverage_checked, " regions, visited / GL texels ", st.gl_texels > 0.0 ? st.coverage_texels / st.gl_texels : 0.0);
}

long envCount(long fallback) { return penumbra::test::envCount("PENUMBRA_INFLUENCE_CASES", fallback); }

}  // namespace

TEST_CASE("cpu: influence regions never miss a shadowed texel (10^5 random + adversarial cases)") {
    Stats st;
    runCases(envCount(100000), penumbra::test::testSeed(), st);
    report(st, "influence never-miss");
    CHECK(st.cases >= 100000);
    CHECK(st.misses == 0);
    CHECK(st.float_texel_misses == 0);
    CHECK(st.sample_inconsistent == 0);
    CHECK(st.coverage_misses == 0);
    CHECK(st.coverage_gl_misses == 0);
    CHECK(st.coverage_checked >= st.cases / 16);
    CHECK(st.shadowed > st.cases);  // the boundary points really are shadowed
    CHECK(st.kinds[static_cast<int>(InfluenceRegionKind::Hull)] > st.cases / 3);
}

TEST_SUITE("stress") {
    TEST_CASE("stress: influence regions never miss (10^6 cases)") {
        Stats st;
        runCases(envCount(1000000), penumbra::test::testSeed(7), st);
        report(st, "influence never-miss (stress)");
        CHECK(st.misses == 0);
        CHECK(st.float_texel_misses == 0);
        CHECK(st.sample_inconsistent == 0);
        CHECK(st.coverage_misses == 0);
        CHECK(st.coverage_gl_misses == 0);
    }
}

TEST_CASE("cpu: influence-region tightness per k (hull area / exact region area)") {
    const uint32_t seed = penumbra::test::testSeed(1);
    for (int sides : {4, 6, 8, 12}) {
        Rng rng(seed);  // the same scenes and triangles for every k
        double sum = 0.0, worst = 0.0, sum_texels = 0.0;
        int used = 0;
        long lattice_misses = 0;
        for (int n = 0; n < 400 && used < 150; ++n) {
            Scenario sc = makeScenario(rng, sides, false);
            const glm::dmat3 linear = pixelLinear(sc.setup), inv_linear = glm::inverse(linear);
            glm::vec3 tri[3];
            makeTriangle(rng, sc, inv_linear, 0, tri);
            if (sc.light.shape != LightShape::Sphere && sc.light.shape != LightShape::Ellipsoid) continue;
            const InfluenceRegion r = penumbra::influenceRegion(tri[0], tri[1], tri[2], sc.setup);
            if (r.kind != InfluenceRegionKind::Hull || r.polygon_count < 3) continue;
            glm::dvec2 lo(1e300), hi(-1e300);
            double area = 0.0;
            for (int i = 0; i < r.polygon_count; ++i) {
                const glm::dvec2 p0(r.polygon[i]), p1(r.polygon[(i + 1) % r.polygon_count]);
                area += p0.x * p1.y - p1.x * p0.y;
                lo = glm::min(lo, p0);
                hi = glm::max(hi, p0);
            }
            area *= 0.5;
            const int lattice = 96;
            const glm::dvec2 cell = (hi - lo) / double(lattice);
            const glm::dvec3 nf(sc.setup.far_plane_local);
            const glm::dvec3 o = sc.setup.projection_center_local;
            long inside = 0;
            for (int j = 0; j < lattice; ++j) {
                for (int i = 0; i < lattice; ++i) {
                    const glm::dvec2 x = lo + (glm::dvec2(i, j) + 0.5) * cell;
                    const glm::dvec3 d = inv_linear * glm::dvec3(x, 1.0);
                    const double lambda = -(glm::dot(nf, o) + sc.setup.far_plane_local.w) / glm::dot(nf, d);
                    if (!(lambda > 0.0)) continue;
                    const glm::dvec3 z = sc.setup.frame.toWorld(o + lambda * d);
                    if (penumbra::influenceShadowedContinuous(sc.setup.frame, glm::dvec3(tri[0]), glm::dvec3(tri[1]),
                                                              glm::dvec3(tri[2]), z)) {
                        ++inside;
                        if (outsideDistance(r, x) > 0.0) ++lattice_misses;
                    }
                }
            }
            if (inside < 100) continue;  // the region is too small for the lattice to measure
            const double exact = inside * cell.x * cell.y;
            const double ratio = area / exact;
            sum += ratio;
            worst = std::max(worst, ratio);
            // Dilated polygon area over the exact region dilated by half a texel (both in px^2).
            double dilated = 0.0;
            for (int i = 0; i < r.count; ++i) {
                const glm::dvec2 p0(r.pixels[i]), p1(r.pixels[(i + 1) % r.count]);
                dilated += p0.x * p1.y - p1.x * p0.y;
            }
            sum_texels += 0.5 * dilated / area;
            ++used;
        }
        REQUIRE(used >= 50);
        MESSAGE("tightness k = ", sides, ": mean hull area / exact region area = ", sum / used, " (worst ", worst, ") over ",
                used, " sphere/ellipsoid cases; dilated / undilated hull area ", sum_texels / used,
                "; lattice points of the exact region outside the hull: ", lattice_misses);
        CHECK(lattice_misses == 0);
        CHECK(sum / used >= 1.0);
    }
}

TEST_CASE("cpu: influence-region setup rejects bad input naming the value") {
    using penumbra::test::contains;
    using penumbra::test::errorOf;
    Light light;
    light.center = glm::dvec3(0, 5, 0);
    light.size = glm::dvec3(0.5);
    const glm::mat4 vp = penumbra::lightViewProjectionForBounds(glm::vec4(0, 5, 0, 1), glm::vec3(-5, 0, -5), glm::vec3(5, 1, 5));
    penumbra::InfluenceRegionOptions o;
    o.grid_width = o.grid_height = 64;
    o.far_plane = penumbra::influenceFarPlaneAtDepth(vp, 6.0);
    CHECK_NOTHROW(penumbra::influenceRegionSetup(light, vp, o));
    auto bad = [&](penumbra::InfluenceRegionOptions x) { return errorOf([&] { penumbra::influenceRegionSetup(light, vp, x); }); };
    auto o1 = o;
    o1.sides = 5;
    CHECK(contains(bad(o1), "sides = 5"));
    o1 = o;
    o1.grid_width = 0;
    CHECK(contains(bad(o1), "grid_width = 0"));
    o1 = o;
    o1.far_plane = glm::dvec4(0.0);
    CHECK(contains(bad(o1), "has no normal"));
    o1 = o;
    o1.far_plane.w = std::nan("");
    CHECK(contains(bad(o1), "not finite"));
    o1 = o;
    o1.far_plane = -penumbra::influenceFarPlaneAtDepth(vp, 6.0);  // orientation does not matter
    CHECK_NOTHROW(penumbra::influenceRegionSetup(light, vp, o1));
    o1.far_plane = glm::dvec4(0, 1, 0, -10);  // y = 10: above the light, behind it for a downward grid
    CHECK(contains(bad(o1), "behind the light"));
    o1.far_plane = glm::dvec4(0, 1, 0, -5.2);  // y = 5.2 cuts the light (radius 0.5)
    CHECK(contains(bad(o1), "touches the light"));
    o1 = o;
    o1.subpixel_bits = 0;
    CHECK(contains(bad(o1), "subpixel_bits = 0"));
    Light zero = light;
    zero.size = glm::dvec3(0.0);
    CHECK(contains(errorOf([&] { penumbra::influenceRegionSetup(zero, vp, o); }), "radius"));
    Light nan_light = light;
    nan_light.center.x = std::nan("");
    CHECK(contains(errorOf([&] { penumbra::influenceRegionSetup(nan_light, vp, o); }), "light.center"));
    glm::mat4 vp_nan = vp;
    vp_nan[2][1] = std::nanf("");
    CHECK(contains(errorOf([&] { penumbra::influenceRegionSetup(light, vp_nan, o); }), "view_projection[2][1]"));
    const glm::mat4 vp_far = penumbra::lightViewProjectionForBounds(glm::vec4(3, 5, 0, 1), glm::vec3(-5, 0, -5), glm::vec3(5, 1, 5));
    CHECK(contains(errorOf([&] { penumbra::influenceRegionSetup(light, vp_far, o); }), "outside the light"));
    const glm::mat4 ortho = penumbra::lightViewProjectionForBounds(glm::vec4(0, 1, 0, 0), glm::vec3(-5, 0, -5), glm::vec3(5, 1, 5));
    CHECK(contains(errorOf([&] { penumbra::influenceRegionSetup(light, ortho, o); }), "not a perspective projection"));
}

TEST_CASE("cpu: per-triangle fallbacks are documented kinds, never NaN") {
    Light light;
    light.center = glm::dvec3(0, 5, 0);
    light.size = glm::dvec3(0.5);
    const glm::mat4 vp = penumbra::lightViewProjectionForBounds(glm::vec4(0, 5, 0, 1), glm::vec3(-5, 0, -5), glm::vec3(5, 1, 5));
    penumbra::InfluenceRegionOptions o;
    o.grid_width = o.grid_height = 64;
    o.far_plane = penumbra::influenceFarPlaneAtDepth(vp, 6.0);
    const InfluenceRegionSetup s = penumbra::influenceRegionSetup(light, vp, o);
    auto region = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c) { return penumbra::influenceRegion(a, b, c, s); };
    const float nan = std::nanf("");
    CHECK(region({nan, 1, 0}, {0, 1, 0}, {1, 1, 0}).kind == InfluenceRegionKind::Dropped);
    CHECK(region({INFINITY, 1, 0}, {0, 1, 0}, {1, 1, 0}).count == 0);
    const InfluenceRegion inside = region({0, 5.1f, 0}, {0.1f, 3, 0}, {0, 3, 0.1f});
    CHECK(inside.kind == InfluenceRegionKind::WholeGrid);
    CHECK((inside.fallback & PENUMBRA_INFLUENCE_FALLBACK_INSIDE_LIGHT) != 0u);
    const InfluenceRegion behind = region({0, 7, 0}, {0.1f, 7, 0}, {0, 7, 0.1f});  // above the light: behind its eye plane
    CHECK(behind.kind == InfluenceRegionKind::WholeGrid);
    CHECK(region({0, -3, 0}, {0.1f, -3, 0}, {0, -3, 0.1f}).kind == InfluenceRegionKind::Culled);  // beyond F
    const InfluenceRegion straddle = region({0, -3, 0}, {0.1f, 3, 0}, {0, 3, 0.1f});
    CHECK(straddle.kind == InfluenceRegionKind::WholeGrid);
    CHECK(straddle.fallback == PENUMBRA_INFLUENCE_FALLBACK_BEYOND_FAR);
    const InfluenceRegion degenerate = region({0.2f, 2, 0.1f}, {0.2f, 2, 0.1f}, {0.2f, 2, 0.1f});
    CHECK(degenerate.kind == InfluenceRegionKind::Hull);  // a point caster still has a penumbra
    const InfluenceRegion normal = region({0, 2, 0}, {0.5f, 2, 0}, {0, 2, 0.5f});
    CHECK(normal.kind == InfluenceRegionKind::Hull);
    CHECK(normal.count >= 3);
    CHECK(normal.count <= s.max_vertices);
    for (int i = 0; i < normal.count; ++i) {
        CHECK(std::isfinite(normal.pixels[i].x));
        CHECK(std::isfinite(normal.pixels[i].y));
    }
    // Every corner of the dilation is one of the three §4.1 cases: the count is at most n + 4.
    CHECK(normal.count <= normal.polygon_count + 4);
}
