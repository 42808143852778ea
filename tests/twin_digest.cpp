// Digest of every CPU twin's output on fixed pseudo-random inputs, one line per twin:
//     <twin> <64-bit digest of every output bit> <number of values hashed>
// tests/CMakeLists.txt builds this program twice — with the project's flags and with
// `-O3 -march=native -ffp-contract=fast` — and ctest (twin_digest_fp_contract, label cpu) runs both
// and requires identical lines: the twins must not change a bit when the compiler may fuse a * b + c
// into an FMA (the GPU side uses `precise`, the twins must not be contractible either), else the
// "GPU == twin bit for bit" tests only hold for one build of the tests.
//
// Inputs come from splitmix64 streams with fixed seeds (no std:: distributions: the same numbers on
// every standard library). No GL context: the twins are pure C++ (sample_lists.hpp and the pipeline
// header still include the GL header, so this links glad for its declarations only).
//
// Usage: twin_digest   (lines starting with "#" describe the build and are not compared)
#include <penumbra/bent_normals.hpp>
#include <penumbra/conservative_raster.hpp>
#include <penumbra/influence_region.hpp>
#include <penumbra/light_lut.hpp>
#include <penumbra/light_samples.hpp>
#include <penumbra/pipelines/alias_free_hard.hpp>
#include <penumbra/reference/visibility.hpp>
#include <penumbra/sample_lists.hpp>
#include <penumbra/scan.hpp>

#include "twin_digest_inputs.hpp"

#include <glm/glm.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

namespace {

using twin_digest::lights;
using twin_digest::makeScene;
using twin_digest::Scene;

/// FNV-1a over the bytes of every value hashed (floats by their bits: -0 != +0, NaN payloads count).
struct Digest {
    uint64_t hash = 0xcbf29ce484222325ull;
    uint64_t values = 0;
    void bytes(const void* data, size_t n) {
        const auto* p = static_cast<const unsigned char*>(data);
        for (size_t i = 0; i < n; ++i) {
            hash ^= p[i];
            hash *= 0x100000001b3ull;
        }
    }
    template <typename T>
    void add(const T& v) {
        static_assert(std::is_trivially_copyable<T>::value, "hash plain values");
        bytes(&v, sizeof v);
        ++values;
    }
    template <typename T>
    void add(const std::vector<T>& v) {
        add(static_cast<uint64_t>(v.size()));
        for (const T& x : v) add(x);
    }
};

void print(const char* twin, const Digest& d) {
    std::printf("%-36s %016llx %llu\n", twin, static_cast<unsigned long long>(d.hash),
                static_cast<unsigned long long>(d.values));
}

// ---- scan ---------------------------------------------------------------------------------------

void scanTwin() {
    uint64_t state = 1;
    Digest d;
    for (size_t n : {size_t(0), size_t(1), size_t(255), size_t(256), size_t(257), size_t(65537)}) {
        std::vector<uint32_t> in(n), out(n);
        for (auto& v : in) v = static_cast<uint32_t>((state = state * 6364136223846793005ull + 1442695040888963407ull) >> 32);
        for (penumbra::ScanKind kind : {penumbra::ScanKind::Exclusive, penumbra::ScanKind::Inclusive}) {
            penumbra::scanCpu(in.data(), out.data(), n, kind);
            d.add(out);
        }
    }
    print("scanCpu", d);
}

void addLists(Digest& d, const penumbra::SampleListsCpu& lists) {
    d.add(lists.counts);
    d.add(lists.offsets);
    d.add(lists.list_positions);
    d.add(lists.list_ids);
    d.add(lists.sample_slots);
    d.add(lists.sample_texels);
    d.add(lists.header);
}

void addFit(Digest& d, const penumbra::LightFrustumFit& fit) {
    d.add(static_cast<uint8_t>(fit.valid));
    d.add(fit.samples);
    d.add(fit.min_uv);
    d.add(fit.max_uv);
    d.add(fit.max_depth);
    d.add(fit.far_distance);
    d.add(fit.crop);
    d.add(fit.view_projection);
    d.add(fit.keys);
}

// ---- sample lists: buffer input, depth input, §4.3 fit -----------------------------------------

void sampleListTwins() {
    const Scene scene = makeScene(2, 20000);
    const uint32_t count = static_cast<uint32_t>(scene.samples.size());
    Digest lists_buffer, fit_buffer, lists_depth, fit_depth, params;
    for (const penumbra::SampleListsLight& light : lights(scene)) {
        for (uint32_t side : {1u, 64u, 257u}) {
            const penumbra::SampleListsSetup setup = penumbra::sampleListsSetup(side, side, count);
            for (bool cull : {true, false}) {
                penumbra::SampleListsOptions options;
                options.cull_back_facing = cull;
                params.add(penumbra::sampleListsParams(setup, light, options));
                addLists(lists_buffer, penumbra::buildSampleListsCpu(setup, light, scene.samples.data(),
                                                                    scene.normals.data(), options));
                addFit(fit_buffer, penumbra::fitLightFrustumCpu(setup, light, scene.samples.data(),
                                                               scene.normals.data(), options));
            }
        }
    }
    // Depth input: a camera looking at the ground, random window depths (some background = 1).
    twin_digest::DepthInput input = twin_digest::makeDepthInput(3);
    penumbra::SampleListsView& view = input.view;
    const std::vector<float>& depth = input.depth;
    const std::vector<glm::vec4>& normals = input.normals;
    for (bool zero_to_one : {false, true}) {
        view.depth_zero_to_one = zero_to_one;
        for (const penumbra::SampleListsLight& light : lights(scene)) {
            const penumbra::SampleListsSetup setup = penumbra::sampleListsSetup(96, 80, depth.size());
            penumbra::SampleListsOptions options;
            options.depth_range = penumbra::LightDepthRange::Unclipped;
            params.add(penumbra::sampleListsParams(setup, light, options, &view));
            addLists(lists_depth,
                     penumbra::buildSampleListsCpu(setup, light, view, depth.data(), normals.data(), options));
            addFit(fit_depth, penumbra::fitLightFrustumCpu(setup, light, view, depth.data(), normals.data(), options));
        }
    }
    // The kernels on identical parameters (computed with contraction off in the inputs TU).
    Digest inputs, classify, transform, view_position, fit_from_keys;
    inputs.add(scene.samples);
    inputs.add(scene.normals);
    inputs.add(input.depth);
    inputs.add(input.view.inverse_view_projection);
    for (const penumbra::SampleListsLight& light : lights(scene)) {
        inputs.add(light.view_projection);
        const penumbra::SampleListsSetup setup = penumbra::sampleListsSetup(64, 64, count);
        const penumbra::SampleListsParams fixed = twin_digest::fixedParams(setup, light, {});
        for (uint32_t id = 0; id < count; ++id) {
            glm::vec4 t;
            const glm::vec4 p = scene.samples[id];
            classify.add(penumbra::detail::classifySample(fixed, p, glm::vec3(scene.normals[id]), &t));
            classify.add(t);
            transform.add(penumbra::detail::transformPoint(fixed.light_texture, p.x, p.y, p.z));
        }
        const penumbra::SampleListsParams fixed_view = twin_digest::fixedParams(
            penumbra::sampleListsSetup(64, 64, input.depth.size()), light, {}, &input.view);
        for (uint32_t id = 0; id < input.depth.size(); ++id) {
            view_position.add(penumbra::detail::viewPosition(fixed_view.view_inverse, id % input.view.width,
                                                             id / input.view.width, input.view.width,
                                                             input.view.height, input.depth[id], false));
        }
        addFit(fit_from_keys, penumbra::lightFrustumFitFromHeader(twin_digest::fixedFitKeys(setup, light, scene), light));
    }
    // Host setup (not a twin): the starting light frustum. The GPU and the twin get the same matrix
    // from one binary, so this only has to be deterministic within a build; printed as "#".
    Digest frustum;
    {
        const auto [lo, hi] = penumbra::viewSampleBounds(scene.samples.data(), scene.samples.size());
        for (const penumbra::SampleListsLight& light : lights(scene)) {
            frustum.add(penumbra::lightViewProjectionForBounds(light.light, lo, hi));
        }
    }
    std::printf("# lightViewProjectionForBounds (host setup) %016llx\n", static_cast<unsigned long long>(frustum.hash));
    print("inputs", inputs);
    print("detail::transformPoint", transform);
    print("detail::classifySample", classify);
    print("detail::viewPosition", view_position);
    print("lightFrustumFitFromHeader", fit_from_keys);
    print("sampleListsParams", params);
    print("buildSampleListsCpu(buffer)", lists_buffer);
    print("fitLightFrustumCpu(buffer)", fit_buffer);
    print("buildSampleListsCpu(depth)", lists_depth);
    print("fitLightFrustumCpu(depth)", fit_depth);
}

// ---- conservative rasterization ----------------------------------------------------------------

void conservativeTwins() {
    const std::vector<glm::vec4> clips = twin_digest::makeClipTriangles(4, 4000);
    const std::vector<glm::ivec2> pixels = twin_digest::makePixels(44, 8);
    Digest raster_fixed, clip_polygons, hull_fixed, hull_exact, raster, polygon, touches, required;
    for (penumbra::ConservativeVariant variant : {penumbra::ConservativeVariant::Fixed6, penumbra::ConservativeVariant::Exact}) {
        penumbra::ConservativeRasterOptions options;
        options.viewport_width = 96;
        options.viewport_height = 64;
        options.variant = variant;
        options.clip_to_box = true;
        const penumbra::ConservativeRasterSetup setup = penumbra::conservativeRasterSetup(options);
        for (size_t t = 0; t + 2 < clips.size(); t += 3) {
            const glm::vec4 clip[3] = {clips[t], clips[t + 1], clips[t + 2]};
            glm::vec2 clipped[penumbra::kConservativeMaxPolygon];
            float clipped_depth[penumbra::kConservativeMaxPolygon];
            const int n = penumbra::detail::conservativeClip(clip, setup.params, clipped, clipped_depth);
            clip_polygons.add(n);
            for (int i = 0; i < n; ++i) {
                clip_polygons.add(clipped[i]);
                clip_polygons.add(clipped_depth[i]);
            }
            const penumbra::ConservativeHull hull = penumbra::conservativeHull(clip, setup);
            Digest& h = variant == penumbra::ConservativeVariant::Fixed6 ? hull_fixed : hull_exact;
            h.add(static_cast<int>(hull.kind));
            h.add(hull.count);
            h.add(hull.pixels);
            h.add(hull.positions);
            h.add(hull.box);
            const penumbra::HullRaster r = penumbra::rasterizeConservativeHull(hull, setup, (t / 3) % 2 ? 1e-3 : 0.0);
            raster.add(r.fragments);
            raster.add(r.uncertain);
            const std::vector<glm::dvec2> poly = penumbra::conservativeReferencePolygon(clip[0], clip[1], clip[2], setup);
            polygon.add(poly);
            for (const glm::ivec2& q : pixels) {
                if (!poly.empty()) touches.add(static_cast<uint8_t>(penumbra::polygonTouchesPixel(poly.data(), poly.size(), q.x, q.y)));
            }
            required.add(penumbra::conservativeRequiredPixels(clip[0], clip[1], clip[2], setup));
        }
        // The raster predicate alone, on hulls computed with contraction off.
        for (const penumbra::ConservativeHull& hull : twin_digest::fixedHulls(clips, setup)) {
            const penumbra::HullRaster r = penumbra::rasterizeConservativeHull(hull, setup, 1e-3);
            raster_fixed.add(r.fragments);
            raster_fixed.add(r.uncertain);
        }
    }
    print("rasterizeConservativeHull(same-hulls)", raster_fixed);
    print("detail::conservativeClip", clip_polygons);
    print("conservativeHull(fixed6)", hull_fixed);
    print("conservativeHull(exact)", hull_exact);
    print("rasterizeConservativeHull", raster);
    print("conservativeReferencePolygon", polygon);
    print("polygonTouchesPixel", touches);
    print("conservativeRequiredPixels", required);
}

// ---- influence regions (sintorn2008 §4.1) --------------------------------------------------------

void influenceRegionTwin() {
    Digest setups, regions, texels, shadowed;
    for (const twin_digest::InfluenceInput& in : twin_digest::makeInfluenceInputs(9, 400)) {
        setups.add(in.setup.params);
        for (size_t t = 0; t + 2 < in.triangles.size(); t += 3) {
            const penumbra::InfluenceRegion r =
                penumbra::influenceRegion(in.triangles[t], in.triangles[t + 1], in.triangles[t + 2], in.setup);
            regions.add(static_cast<int>(r.kind));
            regions.add(r.fallback);
            regions.add(r.point_count);
            for (int i = 0; i < r.point_count; ++i) regions.add(r.points[static_cast<size_t>(i)]);
            regions.add(r.polygon_count);
            for (int i = 0; i < r.polygon_count; ++i) regions.add(r.polygon[static_cast<size_t>(i)]);
            regions.add(r.count);
            for (int i = 0; i < r.count; ++i) regions.add(r.pixels[static_cast<size_t>(i)]);
            const penumbra::HullRaster raster = penumbra::influenceRegionTexels(r, in.setup, (t / 3) % 2 ? 1e-3 : 0.0);
            texels.add(raster.fragments);
            texels.add(raster.uncertain);
            const glm::dvec3 a(in.triangles[t]), b(in.triangles[t + 1]), c(in.triangles[t + 2]);
            const glm::dvec3 p = 0.25 * (a + b + c) + glm::dvec3(0.1, -0.5 - 0.001 * double(t % 50), 0.05);
            shadowed.add(static_cast<uint8_t>(penumbra::influenceShadowedContinuous(in.setup.frame, a, b, c, p)));
        }
    }
    print("influenceRegionSetup(inputs TU)", setups);
    print("influenceRegion", regions);
    print("influenceRegionTexels", texels);
    print("influenceShadowedContinuous", shadowed);
}

// ---- hard shadows: the blocker test and the whole pipeline twin --------------------------------

void hardShadowTwins() {
    const std::vector<glm::dvec3> cases = twin_digest::makeBlockerCases(5, 200000);
    Digest blocks_double, blocks_float, pipeline;
    for (size_t k = 0; k + 4 < cases.size(); k += 5) {
        const size_t i = k / 5;
        const glm::dvec3 &a = cases[k], &b = cases[k + 1], &c = cases[k + 2], &p = cases[k + 3], &l = cases[k + 4];
        const double eps = i % 3 == 0 ? 0.0 : 1e-7;
        const double offset = i % 5 == 0 ? 1e-3 : 0.0;
        blocks_double.add(static_cast<uint8_t>(penumbra::afhBlocks<double>(a, b, c, p, l, eps, offset)));
        const glm::vec3 af(a), bf(b), cf(c), pf(p), lf(l);
        blocks_float.add(static_cast<uint8_t>(
            penumbra::afhBlocks<float>(af, bf, cf, pf, lf, static_cast<float>(eps), static_cast<float>(offset))));
    }
    const Scene scene = makeScene(6, 12000);
    const penumbra::AfhCasters casters{&scene.positions, &scene.indices, &scene.closed};
    for (const penumbra::SampleListsLight& light : lights(scene)) {
        for (penumbra::AfhPrecision precision : {penumbra::AfhPrecision::Exact, penumbra::AfhPrecision::Fast}) {
            penumbra::AliasFreeHardOptions options;
            options.grid_width = options.grid_height = 64;
            options.precision = precision;
            options.directional_reach = 20.0f;
            pipeline.add(penumbra::aliasFreeHardCpu(options, light, scene.samples.data(), scene.normals.data(),
                                                    static_cast<uint32_t>(scene.samples.size()), casters));
        }
    }
    print("afhBlocks<double>", blocks_double);
    print("afhBlocks<float>", blocks_float);
    print("aliasFreeHardCpu", pipeline);
}

// ---- the oracle --------------------------------------------------------------------------------

void oracleTwin() {
    const Scene scene = makeScene(7, 0);
    const penumbra::reference::VisibilityOracle oracle(scene.positions, scene.indices);
    Digest segments, evaluate, hits;
    const std::vector<glm::dvec3> ends = twin_digest::makeSegments(scene, 8, 100000);
    for (size_t i = 0; i + 1 < ends.size(); i += 2) {
        bool tie = false;
        segments.add(static_cast<uint8_t>(oracle.segmentBlocked(ends[i], ends[i + 1], &tie)));
        segments.add(static_cast<uint8_t>(tie));
    }
    const std::vector<glm::dvec3> receivers = twin_digest::makePoints(9, 500, glm::dvec3(-4, 0, -4), glm::dvec3(4, 0, 4));
    const std::vector<glm::dvec3> samples = twin_digest::makePoints(10, 64, glm::dvec3(0, 6, -1), glm::dvec3(2, 8, 1));
    penumbra::reference::VisibilityOptions options;
    options.threads = 1;
    const penumbra::reference::VisibilityResult result = oracle.evaluate(receivers, samples, options);
    evaluate.add(result.blocked);
    evaluate.add(result.ties);
    const std::vector<glm::dvec3> rays = twin_digest::makeRays(11, 20000);
    for (size_t i = 0; i + 1 < rays.size(); i += 2) {
        const penumbra::reference::Hit h = oracle.closestHit(rays[i], rays[i + 1], 0.0, 1e30);
        hits.add(static_cast<uint8_t>(h.hit));
        hits.add(h.t);
        hits.add(h.triangle);
        hits.add(h.u);
        hits.add(h.v);
    }
    print("VisibilityOracle::segmentBlocked", segments);
    print("VisibilityOracle::evaluate", evaluate);
    print("VisibilityOracle::closestHit(t,u,v)", hits);
    // The verdict alone (hit + triangle), without t, u, v.
    Digest verdicts;
    for (size_t i = 0; i + 1 < rays.size(); i += 2) {
        const penumbra::reference::Hit h = oracle.closestHit(rays[i], rays[i + 1], 0.0, 1e30);
        verdicts.add(static_cast<uint8_t>(h.hit));
        verdicts.add(h.triangle);
    }
    print("VisibilityOracle::closestHit(id)", verdicts);
}

// ---- light-sample LUT ---------------------------------------------------------------------------

void lutTwins() {
    // The setup's cells and samples, the generated tables (both mappings, certified) and the float
    // and double lookups: the GPU generator reads the setup's arrays, so they must not move either.
    // (sphereLightSamples is contraction-proof by construction: explicit fma.)
    const std::vector<glm::dvec3> samples = penumbra::reference::sphereLightSamples(glm::dvec3(0.0), 0.999, 160, 5);
    const std::vector<glm::dvec3> planes = twin_digest::makePoints(13, 4000, glm::dvec3(-1.2), glm::dvec3(1.2));
    Digest setup_d, table_d, locate_f, locate_d, exact_f;
    for (const auto mapping : {penumbra::LutNormalMapping::Octahedral, penumbra::LutNormalMapping::Spherical}) {
        penumbra::LightLutOptions options;
        options.resolution = 16;
        options.mapping = mapping;
        options.certified = true;
        const penumbra::LightLutSetup setup = penumbra::lightLutSetup(samples, 160, options);
        setup_d.add(setup.samples);
        setup_d.add(setup.normal_cells);
        setup_d.add(setup.distance_cells);
        table_d.add(penumbra::generateLightLut(setup, penumbra::LutProgress{}, 1));
        for (size_t i = 0; i + 1 < planes.size(); i += 2) {
            const glm::dvec4 plane(planes[i], planes[i + 1].x);
            const penumbra::LutCell f = penumbra::lightLutLocate(setup.params, glm::vec4(plane));
            const penumbra::LutCell d = penumbra::lightLutLocate(setup.params, plane);
            locate_f.add(f.texel), locate_f.add(f.trivial), locate_f.add(static_cast<uint8_t>(f.flip));
            locate_d.add(d.texel), locate_d.add(d.trivial), locate_d.add(static_cast<uint8_t>(d.flip));
            exact_f.add(penumbra::exactBehind(setup, 1, glm::vec4(plane)));
        }
    }
    print("lightLutSetup", setup_d);
    print("generateLightLut", table_d);
    print("lightLutLocate<float>", locate_f);
    print("lightLutLocate<double>", locate_d);
    print("exactBehind<float>", exact_f);
}

// ---- light samples (penumbra/light_samples.hpp): sets, frames, planes, selection ---------------

void lightSampleTwins() {
    Digest sets_d, reference_d, planes_d, select_d;
    uint32_t seed = 1;
    for (uint32_t shape = 0; shape < 4; ++shape)
        for (uint32_t pattern = 0; pattern < 2; ++pattern) {
            penumbra::Light light;
            light.shape = static_cast<penumbra::LightShape>(shape);
            light.center = glm::dvec3(1.25, -3.5, 7.0) * double(shape + 1);
            light.axis_z = glm::dvec3(0.3, -0.7, 1.1);
            light.axis_x = glm::dvec3(1.0, 0.2, -0.1);
            light.size = glm::dvec3(0.7, 0.3, 1.9);
            penumbra::LightSampleOptions options;
            options.count = 96;
            options.sets = 5;
            options.pattern = static_cast<penumbra::SamplePattern>(pattern);
            options.seed = seed++;
            const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, options);
            sets_d.add(sets.local);
            sets_d.add(sets.world);
            for (const glm::dvec3& p : sets.world) sets_d.add(sets.frame.toLocal(p));
            const std::vector<glm::dvec3> n = twin_digest::makePoints(20 + shape, 64, glm::dvec3(-1), glm::dvec3(1));
            for (size_t i = 0; i + 1 < n.size(); i += 2) planes_d.add(sets.frame.planeToLocal(glm::dvec4(n[i], n[i + 1].x)));
        }
    reference_d.add(penumbra::reference::sphereLightSamples(glm::dvec3(1, 2, 3), 0.5, 1000, 42));
    reference_d.add(penumbra::reference::diskLightSamples(glm::dvec3(-1, 0.5, 2), glm::dvec3(0.3, -0.2, 1), 0.75, 1000, 7));
    reference_d.add(penumbra::reference::rectLightSamples(glm::dvec3(0.1, 0.2, 0.3), glm::dvec3(1.1, 0.1, 0),
                                                          glm::dvec3(0, 0.3, 0.9), 13, 7));
    for (uint32_t f = 0; f < 4; ++f)
        for (uint32_t y = 0; y < 64; ++y)
            for (uint32_t x = 0; x < 64; ++x) {
                select_d.add(penumbra::lightSampleSet(x, y, f, 1 + (x ^ y) % 64));
                select_d.add(penumbra::lightSampleRotationTurns(x, y, f, 9));
                select_d.add(penumbra::lightSampleRotationTurnsFloat(x, y, f, 9));
            }
    print("makeLightSampleSets/LightFrame", sets_d);
    print("LightFrame::planeToLocal", planes_d);
    print("reference::*LightSamples", reference_d);
    print("lightSampleSet/RotationTurns", select_d);
}

// ---- bent normals --------------------------------------------------------------------------------

void bentNormalTwins() {
    const std::vector<glm::dvec3> points = twin_digest::makePoints(14, 600, glm::dvec3(-1.0), glm::dvec3(1.0));
    std::vector<glm::vec3> positions(points.begin(), points.end());
    std::vector<uint32_t> indices;
    for (uint32_t i = 0; i + 2 < positions.size(); ++i) indices.insert(indices.end(), {i, i + 1, i + 2});
    const penumbra::BentNormalMesh mesh =
        penumbra::bentNormalMesh(positions.data(), positions.size(), indices.data(), indices.size());
    Digest normals, light, shade;
    normals.add(mesh.face_normals);
    for (const glm::vec4 l : {glm::vec4(0.3f, 2.5f, -0.7f, 0.0f), glm::vec4(-1.5f, 0.2f, 1.1f, 0.4f)})
        for (uint32_t v = 0; v < mesh.vertex_count; ++v) light.add(penumbra::bentLight(mesh, v, positions[v], glm::vec3(l), l.w));
    for (size_t i = 0; i + 1 < points.size(); ++i)
        shade.add(penumbra::bentShade(static_cast<float>(points[i].x), static_cast<float>(points[i + 1].y),
                                      3.0f + static_cast<float>(points[i].z)));
    print("bentNormalMesh (face normals)", normals);
    print("bentLight", light);
    print("bentShade", shade);
}

// ---- helpers the twins call, on identical inputs: which function changes bits ------------------

void helperProbes() {
    const std::vector<glm::dvec3> v = twin_digest::makePoints(12, 40000, glm::dvec3(-1), glm::dvec3(1));
    Digest det_d, det_f, dist_d, dist_f, cross_f, fixed_hull, chain_hull, cross2, glm_dot;
    for (size_t i = 0; i + 3 < v.size(); i += 4) {
        det_d.add(penumbra::detail::afhDet<double>(v[i], v[i + 1], v[i + 2]));
        det_f.add(penumbra::detail::afhDet<float>(glm::vec3(v[i]), glm::vec3(v[i + 1]), glm::vec3(v[i + 2])));
        dist_d.add(penumbra::detail::pointTriangleDistance2<double>(v[i] * 2.0, v[i + 1], v[i + 2], v[i + 3]));
        dist_f.add(penumbra::detail::pointTriangleDistance2<float>(glm::vec3(v[i] * 2.0), glm::vec3(v[i + 1]),
                                                                  glm::vec3(v[i + 2]), glm::vec3(v[i + 3])));
        cross_f.add(penumbra::detail::conservativeCross(glm::vec2(v[i]), glm::vec2(v[i + 1])));
        cross2.add(penumbra::detail::oracle::cross2(v[i].x, v[i].y, v[i + 1].x, v[i + 1].y));
        glm_dot.add(glm::dot(v[i], v[i + 1]));
        // A triangle in pixels, CCW, for the hull builders.
        glm::vec2 tri[3] = {glm::vec2(v[i] * 40.0 + 48.0), glm::vec2(v[i + 1] * 40.0 + 48.0), glm::vec2(v[i + 2] * 40.0 + 48.0)};
        if (penumbra::detail::conservativeCross(tri[1] - tri[0], tri[2] - tri[0]) < 0.0f) std::swap(tri[1], tri[2]);
        glm::vec2 hull[penumbra::kConservativeMaxVertices];
        const int fixed = penumbra::detail::conservativeFixedHull(tri, 0.5f + 0.0625f, hull);
        fixed_hull.add(fixed);
        for (int k = 0; k < fixed; ++k) fixed_hull.add(hull[k]);
        const int chain = penumbra::detail::conservativeChainHull(tri, 3, 0.5f + 0.0625f, hull);
        chain_hull.add(chain);
        for (int k = 0; k < chain; ++k) chain_hull.add(hull[k]);
    }
    print("detail::afhDet<double>", det_d);
    print("detail::afhDet<float>", det_f);
    print("detail::pointTriangleDistance2<double>", dist_d);
    print("detail::pointTriangleDistance2<float>", dist_f);
    print("detail::conservativeCross", cross_f);
    print("detail::conservativeFixedHull", fixed_hull);
    print("detail::conservativeChainHull", chain_hull);
    print("detail::oracle::cross2", cross2);
    // Not compared (a "#" line): shows that a plain glm::dot contracts, so a twin calling glm::dot,
    // glm::cross, glm::length or glm matrix products on values it mirrors is contractible too.
    std::printf("# glm::dot(dvec3) %016llx (differs between the builds when FMA contraction is on)\n",
                static_cast<unsigned long long>(glm_dot.hash));
}

}  // namespace

int main() {
#if defined(__FMA__)
    std::printf("# build: FMA instructions available (-mfma), ");
#else
    std::printf("# build: no FMA instructions, ");
#endif
#if defined(__FP_FAST_FMA)
    std::printf("__FP_FAST_FMA\n");
#else
    std::printf("no __FP_FAST_FMA\n");
#endif
    scanTwin();
    sampleListTwins();
    conservativeTwins();
    influenceRegionTwin();
    hardShadowTwins();
    oracleTwin();
    lutTwins();
    bentNormalTwins();
    lightSampleTwins();
    helperProbes();
    return 0;
}
