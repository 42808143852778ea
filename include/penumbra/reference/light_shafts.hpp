// penumbra/reference/light_shafts.hpp — ground truths and the CPU twin of billeter2010's light-volume
// render (issue 12): per eye ray, the airlight of a spot light's lit region
//   1. from the light volume (penumbra/light_volume.hpp): over the ray's crossings of the closed
//      volume, sum_{t < D} s A(t) + A(D) sum_{t >= D} s, s = +1 where the ray leaves the volume and
//      -1 where it enters, D the scene's depth along the ray (the clamp), A the cumulative airlight
//      from the eye (penumbra/airlight.hpp) — what the GPU render accumulates (crossings beyond the
//      scene only count, so hidden shafts cancel exactly);
//   2. by ray marching the same shadow map (any step count; each lit step's airlight integrated by
//      the density's midpoint rule, or exactly from the cumulative airlight): a point is lit when it
//      is inside the light's frustum and no deeper than the map, sampled either at the nearest
//      texel (what a ray marcher in an engine does) or on the lattice surface the static volume is
//      made of (then the converged march and the static volume's airlight agree up to quadrature);
//   3. by ray marching with exact visibility: lit = inside the frustum and the segment to the
//      light unblocked by the scene (the visibility oracle, double).
// Needs: GLM, the C++17 standard library, the oracles of this folder. No GL. Not for per-frame use.
#ifndef PENUMBRA_REFERENCE_LIGHT_SHAFTS_HPP
#define PENUMBRA_REFERENCE_LIGHT_SHAFTS_HPP

#include "penumbra/error.hpp"
#include "penumbra/light_volume.hpp"
#include "penumbra/reference/transmittance.hpp"
#include "penumbra/reference/visibility.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace penumbra::reference {

/// The light volume in world space, with an all-crossings ray query (the transmittance oracle's
/// watertight BVH traversal) and each triangle's outward normal.
class LightVolumeRaycaster {
public:
    LightVolumeRaycaster(const LightVolumeMesh& mesh, const std::vector<float>& corners, const glm::dmat4& inverse_view_projection,
                         const glm::dvec3& light_position)
        : LightVolumeRaycaster(worldTriangles(mesh, corners, inverse_view_projection, light_position)) {}

    /// Signed crossings of the ray eye + t dir, 0 < t < t_max, sorted by t: +1 leaving the volume, -1
    /// entering. Crossings at the same t (a shared edge or vertex) are merged into the sign of their
    /// sum (two faces of one side: one crossing; a grazed silhouette edge: none).
    std::vector<std::pair<double, int>> crossings(const glm::dvec3& eye, const glm::dvec3& dir, double t_max) const {
        const RayTransmittance<double> ray = oracle_.transmittanceAlongRay(eye, dir, t_max);
        std::vector<std::pair<double, int>> out;
        for (size_t i = 0; i < ray.steps.size();) {
            size_t j = i;
            int sum = 0;
            for (; j < ray.steps.size() && ray.steps[j].t == ray.steps[i].t; ++j)
                sum += glm::dot(normals_[ray.steps[j].triangle], dir) > 0.0 ? 1 : -1;
            if (sum != 0) out.emplace_back(ray.steps[i].t, sum > 0 ? 1 : -1);
            i = j;
        }
        return out;
    }

    /// billeter2010's sum for one eye ray (unit dir), the crossings clamped to the scene depth D:
    /// sum_{t < D} s A(t) + A(D) sum_{t >= D} s. `airlight(t)` is the cumulative airlight from the
    /// eye. `far` bounds the ray (beyond the volume).
    template <typename Airlight>
    double airlight(const glm::dvec3& eye, const glm::dvec3& dir, double scene_depth, double far, Airlight&& cumulative) const {
        double before = 0.0;
        int beyond = 0;
        for (const auto& [t, sign] : crossings(eye, dir, far)) {
            if (t < scene_depth) before += sign * cumulative(t);
            else beyond += sign;
        }
        return before + (beyond != 0 ? beyond * cumulative(scene_depth) : 0.0);
    }

    size_t triangles() const { return normals_.size(); }

private:
    struct World {
        std::vector<glm::dvec3> positions;
        std::vector<uint32_t> indices;
    };
    explicit LightVolumeRaycaster(World world)
        : oracle_(world.positions, world.indices, 1.0), normals_(world.indices.size() / 3) {
        for (size_t t = 0; t < normals_.size(); ++t) {
            const glm::dvec3& a = world.positions[world.indices[3 * t]];
            normals_[t] = glm::cross(world.positions[world.indices[3 * t + 1]] - a, world.positions[world.indices[3 * t + 2]] - a);
        }
    }
    static World worldTriangles(const LightVolumeMesh& mesh, const std::vector<float>& corners, const glm::dmat4& inverse_vp,
                                const glm::dvec3& light_position) {
        World world;
        world.positions.reserve(mesh.triangles.size());
        world.indices.reserve(mesh.triangles.size());
        for (uint32_t vertex : mesh.triangles) {
            world.indices.push_back(static_cast<uint32_t>(world.positions.size()));
            world.positions.push_back(lightVolumePosition(vertex, mesh.resolution, corners, inverse_vp, light_position));
        }
        return world;
    }

    TransmittanceOracle oracle_;
    std::vector<glm::dvec3> normals_;  // outward, not normalised
};

/// How a ray march decides that a point is lit by the shadow map.
enum class ShadowMapLookup {
    Nearest,  ///< depth <= the nearest texel's (an engine's ray marcher)
    Lattice,  ///< depth <= the static volume's floor (the lattice depths, two triangles per unit cell)
};

/// The spot light's frustum and shadow map as a ray marcher sees them.
struct ShadowMapView {
    glm::dmat4 view_projection{1.0};
    uint32_t resolution = 0;
    const std::vector<float>* depth = nullptr;    ///< R^2 texels (Nearest)
    const std::vector<float>* corners = nullptr;  ///< (R + 1)^2 lattice depths (Lattice)
};

/// Post-projective (NDC xy, window depth) of x, and whether it is inside the frustum.
inline bool shadowMapProject(const ShadowMapView& view, const glm::dvec3& x, glm::dvec3& window) {
    const glm::dvec4 clip = view.view_projection * glm::dvec4(x, 1.0);
    if (!(clip.w > 0.0)) return false;
    const glm::dvec3 ndc = glm::dvec3(clip) / clip.w;
    if (std::abs(ndc.x) > 1.0 || std::abs(ndc.y) > 1.0 || std::abs(ndc.z) > 1.0) return false;
    window = glm::dvec3((ndc.x + 1.0) * 0.5 * view.resolution, (ndc.y + 1.0) * 0.5 * view.resolution, 0.5 * ndc.z + 0.5);
    return true;
}

/// Whether x is lit according to the shadow map (inside the frustum and no deeper than it).
inline bool shadowMapLit(const ShadowMapView& view, ShadowMapLookup lookup, const glm::dvec3& x) {
    glm::dvec3 w;
    if (!shadowMapProject(view, x, w)) return false;
    const uint32_t r = view.resolution;
    if (lookup == ShadowMapLookup::Nearest) {
        const uint32_t i = std::min(r - 1, static_cast<uint32_t>(w.x)), j = std::min(r - 1, static_cast<uint32_t>(w.y));
        return w.z <= double((*view.depth)[size_t(j) * r + i]);
    }
    // The static floor: unit cell (i, j), diagonal (i, j) - (i + 1, j + 1), as tessellateLightVolume.
    const uint32_t i = std::min(r - 1, static_cast<uint32_t>(w.x)), j = std::min(r - 1, static_cast<uint32_t>(w.y));
    const double fx = w.x - i, fy = w.y - j;
    const auto c = [&](uint32_t a, uint32_t b) { return double((*view.corners)[size_t(b) * (r + 1) + a]); };
    const double floor = fx >= fy ? c(i, j) + fx * (c(i + 1, j) - c(i, j)) + fy * (c(i + 1, j + 1) - c(i + 1, j))
                                  : c(i, j) + fy * (c(i, j + 1) - c(i, j)) + fx * (c(i + 1, j + 1) - c(i, j + 1));
    return w.z <= floor;
}

/// The part [t_begin, t_end] of the ray eye + t dir, 0 <= t <= t_max, inside the light's frustum
/// (its six clip planes, w > 0); t_begin > t_end when the ray misses it. Nothing outside is lit, so
/// a march needs its steps only here.
inline std::pair<double, double> frustumInterval(const ShadowMapView& view, const glm::dvec3& eye, const glm::dvec3& dir, double t_max) {
    const glm::dvec4 c0 = view.view_projection * glm::dvec4(eye, 1.0), c1 = view.view_projection * glm::dvec4(dir, 0.0);
    double lo = 0.0, hi = t_max;
    // a + b t >= 0 for each plane: w +- x, w +- y, w +- z (and w itself).
    const double a[7] = {c0.w + c0.x, c0.w - c0.x, c0.w + c0.y, c0.w - c0.y, c0.w + c0.z, c0.w - c0.z, c0.w};
    const double b[7] = {c1.w + c1.x, c1.w - c1.x, c1.w + c1.y, c1.w - c1.y, c1.w + c1.z, c1.w - c1.z, c1.w};
    for (int k = 0; k < 7; ++k) {
        if (b[k] == 0.0) {
            if (a[k] < 0.0) return {1.0, 0.0};
        } else if (b[k] > 0.0) {
            lo = std::max(lo, -a[k] / b[k]);
        } else {
            hi = std::min(hi, -a[k] / b[k]);
        }
    }
    return {lo, hi};
}

/// Midpoint-rule ray march of the airlight density over [t_begin, t_end] in `steps` steps, lit by
/// `lit(x)`; density(t) is the airlight integrand at distance t along the ray.
template <typename Lit, typename Density>
double rayMarch(const glm::dvec3& eye, const glm::dvec3& dir, double t_begin, double t_end, uint32_t steps, Lit&& lit,
                Density&& density) {
    PENUMBRA_CHECK(steps >= 1, "rayMarch: steps must be >= 1 (got ", steps, ")");
    if (!(t_end > t_begin)) return 0.0;
    const double dt = (t_end - t_begin) / steps;
    double sum = 0.0;
    for (uint32_t k = 0; k < steps; ++k) {
        const double t = t_begin + (k + 0.5) * dt;
        if (lit(eye + t * dir)) sum += density(t);
    }
    return sum * dt;
}

/// The same march with each lit step integrated exactly: sum over the steps whose midpoint is lit
/// of cumulative(t_end) - cumulative(t_begin), cumulative(t) the airlight from the eye to t. The
/// only error left is the lit region's boundary within one step (no quadrature error at the
/// light's 1 / r^2 peak, which a midpoint sum of the density needs many steps to resolve).
template <typename Lit, typename Cumulative>
double rayMarchExact(const glm::dvec3& eye, const glm::dvec3& dir, double t_begin, double t_end, uint32_t steps, Lit&& lit,
                     Cumulative&& cumulative) {
    PENUMBRA_CHECK(steps >= 1, "rayMarchExact: steps must be >= 1 (got ", steps, ")");
    if (!(t_end > t_begin)) return 0.0;
    const double dt = (t_end - t_begin) / steps;
    double sum = 0.0, before = cumulative(t_begin);
    for (uint32_t k = 0; k < steps; ++k) {
        const double after = cumulative(t_begin + (k + 1) * dt);
        if (lit(eye + (t_begin + (k + 0.5) * dt) * dir)) sum += after - before;
        before = after;
    }
    return sum;
}

/// Exact visibility: x is lit when inside the frustum and nothing of the scene blocks x -> light.
inline bool oracleLit(const ShadowMapView& frustum, const VisibilityOracle& scene, const glm::dvec3& light_position, const glm::dvec3& x) {
    glm::dvec3 w;
    if (!shadowMapProject(frustum, x, w)) return false;
    return !scene.closestHit(x, light_position - x, 1e-9, 1.0 - 1e-9).hit;
}

}  // namespace penumbra::reference

#endif
