// Inputs of tests/twin_digest.cpp (see twin_digest_inputs.hpp): always compiled -ffp-contract=off.
#include "twin_digest_inputs.hpp"

#include <penumbra/pipelines/alias_free_hard.hpp>

#include <glm/gtc/matrix_transform.hpp>

namespace twin_digest {
namespace {

/// splitmix64 (Steele, Lea, Flood 2014): the same stream everywhere.
struct Rng {
    uint64_t state;
    explicit Rng(uint64_t seed) : state(seed) {}
    uint64_t next() {
        uint64_t z = (state += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    uint32_t u32() { return static_cast<uint32_t>(next() >> 32); }
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    float uniformf(float lo, float hi) { return static_cast<float>(uniform(lo, hi)); }
    glm::vec3 vec3(float lo, float hi) { return {uniformf(lo, hi), uniformf(lo, hi), uniformf(lo, hi)}; }
    glm::dvec3 dvec3(double lo, double hi) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }
};

}  // namespace

Scene makeScene(uint64_t seed, uint32_t sample_count) {
    Rng rng(seed);
    Scene s;
    const int n = 8;  // ground: n x n quads on [-4, 4]^2 at y = 0, slightly jittered
    for (int z = 0; z <= n; ++z) {
        for (int x = 0; x <= n; ++x) {
            s.positions.emplace_back(-4.0f + 8.0f * x / n, rng.uniformf(-0.01f, 0.01f), -4.0f + 8.0f * z / n);
        }
    }
    for (int z = 0; z < n; ++z) {
        for (int x = 0; x < n; ++x) {
            const uint32_t a = z * (n + 1) + x, b = a + 1, c = a + n + 1, e = c + 1;
            s.indices.insert(s.indices.end(), {a, c, b, b, c, e});
        }
    }
    for (int t = 0; t < 40; ++t) {  // floating casters
        const glm::vec3 centre(rng.uniformf(-3.0f, 3.0f), rng.uniformf(0.3f, 2.5f), rng.uniformf(-3.0f, 3.0f));
        const uint32_t base = static_cast<uint32_t>(s.positions.size());
        for (int k = 0; k < 3; ++k) s.positions.push_back(centre + rng.vec3(-0.6f, 0.6f));
        s.indices.insert(s.indices.end(), {base, base + 1, base + 2});
    }
    s.closed.assign(s.indices.size() / 3, 0);
    const uint32_t triangles = static_cast<uint32_t>(s.indices.size() / 3);
    for (uint32_t i = 0; i < sample_count; ++i) {
        if (rng.u32() % 16 == 0) {  // background
            s.samples.emplace_back(0.0f);
            s.normals.emplace_back(0.0f);
            continue;
        }
        const uint32_t t = rng.u32() % triangles;
        const glm::vec3 a = s.positions[s.indices[3 * t]], b = s.positions[s.indices[3 * t + 1]],
                        c = s.positions[s.indices[3 * t + 2]];
        float u = rng.uniformf(0.0f, 1.0f), v = rng.uniformf(0.0f, 1.0f);
        if (u + v > 1.0f) {
            u = 1.0f - u;
            v = 1.0f - v;
        }
        const glm::vec3 p = a + u * (b - a) + v * (c - a);
        glm::vec3 normal = glm::normalize(glm::cross(b - a, c - a));
        if (normal.y < 0.0f) normal = -normal;
        s.samples.emplace_back(p, 1.0f);
        s.normals.emplace_back(normal, 0.0f);
    }
    return s;
}

// The light matrices, built here rather than with penumbra::lightViewProjectionForBounds: that
// inline function is also compiled into the digest TU (with contraction on in one build), and the
// linker keeps one out-of-line copy for both TUs — the inputs would then differ between builds.
// glm's small templates inline into this TU (compiled with -ffp-contract=off).
glm::mat4 lightMatrix(const glm::vec4& l, const glm::vec3& lo, const glm::vec3& hi) {
    const glm::vec3 center = 0.5f * (lo + hi);
    const float radius = 0.5f * glm::length(hi - lo);
    if (l.w == 0.0f) {
        const glm::vec3 dir = glm::normalize(glm::vec3(l));
        const glm::vec3 eye = center + dir * (2.0f * radius);
        return glm::ortho(-radius, radius, -radius, radius, 0.5f * radius, 3.5f * radius) *
               glm::lookAt(eye, center, glm::vec3(0, 0, 1));
    }
    const glm::vec3 eye(l);
    const float distance = glm::length(center - eye);
    const float near_plane = std::max(0.5f * (distance - radius), 0.01f);
    const float fov = 2.0f * std::atan(radius / std::max(distance - radius, 0.25f * radius)) * 1.1f;
    return glm::perspective(std::min(fov, 2.9f), 1.0f, near_plane, distance + 2.0f * radius) *
           glm::lookAt(eye, center, glm::vec3(0, 0, 1));
}

std::vector<penumbra::SampleListsLight> lights(const Scene& scene) {
    glm::vec3 lo(1e30f), hi(-1e30f);
    for (const glm::vec4& p : scene.samples) {
        lo = glm::min(lo, glm::vec3(p));
        hi = glm::max(hi, glm::vec3(p));
    }
    std::vector<penumbra::SampleListsLight> out;
    for (const glm::vec4 l : {glm::vec4(1.5f, 9.0f, -2.0f, 1.0f), glm::vec4(-6.0f, 4.0f, 5.0f, 1.0f),
                              glm::vec4(glm::normalize(glm::vec3(0.3f, 1.0f, 0.2f)), 0.0f)}) {
        penumbra::SampleListsLight light;
        light.light = l;
        light.view_projection = lightMatrix(l, lo, hi);
        out.push_back(light);
    }
    return out;
}

DepthInput makeDepthInput(uint64_t seed) {
    Rng rng(seed);
    DepthInput in;
    in.view.width = 160;
    in.view.height = 120;
    const glm::mat4 view_projection = glm::perspective(0.9f, 160.0f / 120.0f, 0.1f, 40.0f) *
                                      glm::lookAt(glm::vec3(0, 5, 9), glm::vec3(0), glm::vec3(0, 1, 0));
    in.view.inverse_view_projection = glm::inverse(view_projection);
    in.depth.resize(size_t(in.view.width) * in.view.height);
    in.normals.resize(in.depth.size());
    for (size_t i = 0; i < in.depth.size(); ++i) {
        in.depth[i] = rng.u32() % 10 == 0 ? 1.0f : rng.uniformf(0.9f, 0.999f);
        in.normals[i] = glm::vec4(glm::normalize(rng.vec3(-0.3f, 0.3f) + glm::vec3(0, 1, 0)), 0.0f);
    }
    return in;
}

penumbra::SampleListsParams fixedParams(const penumbra::SampleListsSetup& setup, const penumbra::SampleListsLight& light,
                                        const penumbra::SampleListsOptions& options,
                                        const penumbra::SampleListsView* view) {
    return penumbra::sampleListsParams(setup, light, options, view);
}

penumbra::SampleListsHeader fixedFitKeys(const penumbra::SampleListsSetup& setup, const penumbra::SampleListsLight& light,
                                         const Scene& scene) {
    const penumbra::SampleListsParams params = penumbra::sampleListsParams(setup, light);
    return penumbra::detail::fitKeysCpu(setup, params, [&](uint32_t id, glm::vec4& p, glm::vec3& n) {
        p = scene.samples[id];
        n = glm::vec3(scene.normals[id]);
    });
}

std::vector<glm::vec4> makeClipTriangles(uint64_t seed, int count) {
    Rng rng(seed);
    std::vector<glm::vec4> out;
    for (int t = 0; t < count; ++t) {
        glm::vec4 clip[3];
        const int kind = t % 4;  // 0: small, 1: large, 2: crossing the near plane, 3: thin
        for (auto& c : clip) {
            const float w = kind == 2 ? rng.uniformf(-0.5f, 2.0f) : rng.uniformf(0.5f, 3.0f);
            const float r = kind == 1 ? 3.0f : 1.0f;
            c = glm::vec4(rng.uniformf(-r, r) * w, rng.uniformf(-r, r) * w, rng.uniformf(-1.0f, 1.0f) * w, w);
        }
        if (kind == 3) clip[2] = clip[0] + (clip[1] - clip[0]) * rng.uniformf(0.0f, 1.0f) + glm::vec4(1e-5f, 0, 0, 0);
        out.insert(out.end(), clip, clip + 3);
    }
    return out;
}

std::vector<penumbra::ConservativeHull> fixedHulls(const std::vector<glm::vec4>& clips,
                                                   const penumbra::ConservativeRasterSetup& setup) {
    std::vector<penumbra::ConservativeHull> out;
    for (size_t t = 0; t + 2 < clips.size(); t += 3) out.push_back(penumbra::conservativeHull(clips[t], clips[t + 1], clips[t + 2], setup));
    return out;
}

std::vector<glm::ivec2> makePixels(uint64_t seed, int count) {
    Rng rng(seed);
    std::vector<glm::ivec2> out;
    for (int i = 0; i < count; ++i) out.emplace_back(static_cast<int>(rng.u32() % 96), static_cast<int>(rng.u32() % 64));
    return out;
}

std::vector<glm::dvec3> makeBlockerCases(uint64_t seed, int count) {
    Rng rng(seed);
    std::vector<glm::dvec3> out;
    for (int i = 0; i < count; ++i) {
        const glm::dvec3 a = rng.dvec3(-1, 1), b = rng.dvec3(-1, 1), c = rng.dvec3(-1, 1);
        glm::dvec3 p = rng.dvec3(-2, 2);
        const glm::dvec3 l = rng.dvec3(-2, 2) + glm::dvec3(0, 3, 0);
        if (i % 8 == 0) p = a + 0.3 * (b - a) + 0.3 * (c - a);  // on the triangle: the coplanar rule
        out.insert(out.end(), {a, b, c, p, l});
    }
    return out;
}

std::vector<glm::dvec3> makeSegments(const Scene& scene, uint64_t seed, int count) {
    Rng rng(seed);
    std::vector<glm::dvec3> out;
    for (int i = 0; i < count; ++i) {
        glm::dvec3 p(rng.uniform(-4, 4), rng.uniform(-0.02, 0.5), rng.uniform(-4, 4));
        if (i % 4 == 0) {  // on a caster triangle
            const uint32_t t = rng.u32() % static_cast<uint32_t>(scene.indices.size() / 3);
            const glm::dvec3 a(scene.positions[scene.indices[3 * t]]), b(scene.positions[scene.indices[3 * t + 1]]),
                c(scene.positions[scene.indices[3 * t + 2]]);
            p = a + 0.25 * (b - a) + 0.4 * (c - a);
        }
        const glm::dvec3 l = rng.dvec3(-5, 5) + glm::dvec3(0, 6, 0);
        out.insert(out.end(), {p, l});
    }
    return out;
}

std::vector<glm::dvec3> makeRays(uint64_t seed, int count) {
    Rng rng(seed);
    std::vector<glm::dvec3> out;
    for (int i = 0; i < count; ++i) {
        const glm::dvec3 o = rng.dvec3(-5, 5) + glm::dvec3(0, 8, 0);
        const glm::dvec3 dir = rng.dvec3(-1, 1) - glm::dvec3(0, 1.5, 0);
        out.insert(out.end(), {o, dir});
    }
    return out;
}

std::vector<glm::dvec3> makePoints(uint64_t seed, int count, const glm::dvec3& lo, const glm::dvec3& hi) {
    Rng rng(seed);
    std::vector<glm::dvec3> out;
    for (int i = 0; i < count; ++i) out.emplace_back(rng.uniform(lo.x, hi.x), rng.uniform(lo.y, hi.y), rng.uniform(lo.z, hi.z));
    return out;
}

std::vector<InfluenceInput> makeInfluenceInputs(uint64_t seed, int triangles_per_setup) {
    Rng rng(seed);
    std::vector<InfluenceInput> out;
    const int sides[4] = {4, 6, 8, 12};
    for (int i = 0; i < 8; ++i) {
        penumbra::Light light;
        light.shape = i % 3 == 0 ? penumbra::LightShape::Sphere : i % 3 == 1 ? penumbra::LightShape::Ellipsoid
                                                                              : penumbra::LightShape::Disk;
        // Not a float on purpose (the setup moves the frame to the float centre and inflates). The
        // sum is formed in double explicitly: GCC -O3 was seen to drop a float round trip here.
        const glm::dvec3 jitter(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0));
        light.center = jitter + glm::dvec3(0.0, 6.0, 0.0);
        light.size = glm::dvec3(rng.uniform(0.1, 0.8), rng.uniform(0.1, 0.8), rng.uniform(0.1, 0.8));
        light.axis_z = glm::dvec3(rng.uniform(-0.3, 0.3), 1.0, rng.uniform(-0.3, 0.3));
        const glm::vec3 lo(-4, 0, -4), hi(4, 1, 4);
        const glm::mat4 vp = penumbra::lightViewProjectionForBounds(glm::vec4(glm::vec3(light.center), 1.0f), lo, hi);
        penumbra::InfluenceRegionOptions o;
        o.grid_width = 96;
        o.grid_height = 64;
        o.sides = sides[i % 4];
        o.cut_by_supporting_plane = i >= 4;
        o.far_plane = i % 2 ? penumbra::influenceFarPlaneAtDepth(vp, 8.0) : glm::dvec4(0.0, 1.0, 0.0, 0.25);
        InfluenceInput in{penumbra::influenceRegionSetup(light, vp, o), {}};
        for (int t = 0; t < triangles_per_setup; ++t) {
            const glm::vec3 base(rng.uniformf(-4.0f, 4.0f), rng.uniformf(0.3f, 5.5f), rng.uniformf(-4.0f, 4.0f));
            const float size = t % 4 == 0 ? 2.0f : t % 4 == 1 ? 0.02f : 0.4f;
            in.triangles.push_back(base);
            in.triangles.push_back(base + size * rng.vec3(-1.0f, 1.0f));
            in.triangles.push_back(t % 7 == 3 ? base : base + size * rng.vec3(-1.0f, 1.0f));
        }
        out.push_back(in);
    }
    return out;
}

}  // namespace twin_digest
