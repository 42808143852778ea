// soft_shadows — penumbra's main job: render a scene lit by a spherical light with sample-based
// soft shadows and write a PNG, optionally with a one-line JSON report on stdout.
//
//   soft_shadows [--scene builtin:torus_knot|builtin:columns|builtin:hairball|builtin:grass|PATH.obj]
//                [--light-pos x,y,z] [--light-radius r] [--samples N] [--width W] [--height H]
//                [--mode reference] [--out FILE.png] [--json] [--no-ground]
//
// Modes
//   reference (default): every view sample's visibility of N light samples from the exact
//       double-precision oracle (penumbra/reference/visibility.hpp) on the CPU: soft shadows.
//   hard: the GPU alias-free hard-shadow pipeline (penumbra/pipelines/alias_free_hard.hpp,
//       sintorn2008 §3) from the light's centre, on a headless GL context (PENUMBRA_GL=egl|osmesa);
//       --reference adds the oracle's verdict for the same samples and light point to the JSON
//       (mismatched, ties, samples).
#include <penumbra/gl/headless.hpp>
#include <penumbra/pipelines/alias_free_hard.hpp>
#include <penumbra/reference/light_samples.hpp>
#include <penumbra/reference/visibility.hpp>
#include <penumbra/scene/gl_scene.hpp>
#include <penumbra/scene/image.hpp>
#include <penumbra/scene/obj.hpp>
#include <penumbra/scene/scene.hpp>
#include <penumbra/version.hpp>

#include <glm/glm.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <cstdint>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

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
};

[[noreturn]] void usage(const std::string& problem) {
    std::fprintf(stderr,
                 "soft_shadows: %s\n"
                 "usage: soft_shadows [--scene builtin:NAME|PATH.obj] [--light-pos x,y,z] [--light-radius r]\n"
                 "                    [--samples N] [--width W] [--height H] [--mode reference|hard]\n"
                 "                    [--reference] [--out FILE.png] [--json] [--no-ground]\n"
                 "built-in scenes: torus_knot columns hairball grass\n",
                 problem.c_str());
    std::exit(2);
}

double parseNumber(const std::string& text, const char* what) {
    char* end = nullptr;
    double v = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0' || !std::isfinite(v)) usage(std::string("bad ") + what + " '" + text + "'");
    return v;
}

uint32_t parseCount(const std::string& text, const char* what, uint32_t min, uint32_t max) {
    double v = parseNumber(text, what);
    if (v != std::floor(v) || v < min || v > max) {
        usage(std::string(what) + " must be a whole number in [" + std::to_string(min) + ", " + std::to_string(max) +
              "], got '" + text + "'");
    }
    return static_cast<uint32_t>(v);
}

Args parseArgs(int argc, char** argv) {
    Args a;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) usage(arg + " needs a value");
            return argv[++i];
        };
        if (arg == "--scene") a.scene = value();
        else if (arg == "--mode") a.mode = value();
        else if (arg == "--out") a.out = value();
        else if (arg == "--json") a.json = true;
        else if (arg == "--no-ground") a.ground = false;
        else if (arg == "--reference") a.reference = true;
        else if (arg == "--samples") a.samples = parseCount(value(), "--samples", 1, 1u << 16);
        else if (arg == "--width") a.width = parseCount(value(), "--width", 1, 16384);
        else if (arg == "--height") a.height = parseCount(value(), "--height", 1, 16384);
        else if (arg == "--light-radius") {
            a.light_radius = parseNumber(value(), "--light-radius");
            if (a.light_radius < 0) usage("--light-radius must be >= 0");
        } else if (arg == "--light-pos") {
            std::string v = value();
            std::replace(v.begin(), v.end(), ',', ' ');
            std::istringstream in(v);
            std::string x, y, z, extra;
            in >> x >> y >> z;
            if (z.empty() || (in >> extra)) usage("--light-pos takes x,y,z");
            a.light_pos = {parseNumber(x, "--light-pos x"), parseNumber(y, "--light-pos y"),
                           parseNumber(z, "--light-pos z")};
            a.has_light_pos = true;
        } else if (arg == "--help" || arg == "-h") {
            usage("help");
        } else {
            usage("unknown argument '" + arg + "'");
        }
    }
    if (a.mode != "reference" && a.mode != "hard") usage("unknown --mode '" + a.mode + "' (available: reference, hard)");
    return a;
}

double msSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

std::string jsonEscape(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (c == '"' || c == '\\') out += '\\';
        if (static_cast<unsigned char>(c) < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", c);
            out += buf;
        } else {
            out += c;
        }
    }
    return out;
}

// Runs body(i) for i in [0, n) on all cores.
template <typename Body>
void parallelFor(size_t n, Body body) {
    unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t) {
        pool.emplace_back([&, t] {
            for (size_t i = t; i < n; i += threads) body(i);
        });
    }
    for (auto& th : pool) th.join();
}


// --mode hard: the GPU alias-free hard-shadow pipeline from the light's centre.
int runHard(const Args& args, const penumbra::scene::Scene& scene, const penumbra::reference::VisibilityOracle& oracle,
            const std::vector<uint8_t>& material, const glm::dvec3& light_pos, double load_ms,
            std::chrono::steady_clock::time_point t_start) {
    auto t0 = std::chrono::steady_clock::now();
    penumbra::gl::HeadlessContext context;
    penumbra::scene::GpuScene gpu(scene);
    const uint32_t w = args.width, h = args.height;
    penumbra::scene::GBuffer gbuffer(w, h);
    gbuffer.render(gpu, scene.camera.projection(float(w) / float(h)) * scene.camera.view());
    const auto positions = gbuffer.positionBuffer().download<glm::vec4>();
    const auto faces = gbuffer.faceBuffer().download<glm::vec4>();
    std::vector<float> shading(size_t(w) * h * 4);
    glGetTextureImage(gbuffer.shadingNormalTexture(), 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(shading.size() * 4),
                      shading.data());
    glFinish();
    const double gbuffer_ms = msSince(t0);

    // The light must see the view samples: a starting frustum around their box, then §4.3 fitting.
    size_t view_samples = 0;
    const auto [lo, hi] = penumbra::viewSampleBounds(positions.data(), positions.size(), &view_samples);
    penumbra::SampleListsLight light;
    light.light = glm::vec4(glm::vec3(light_pos), 1.0f);
    light.view_projection = penumbra::lightViewProjectionForBounds(light.light, lo, hi);
    penumbra::AliasFreeHardOptions options;
    options.grid_width = w;
    options.grid_height = h;
    options.count_work = true;
    penumbra::AliasFreeHardShadows pipeline(options);
    std::vector<uint8_t> closed;
    for (const auto& r : gpu.ranges()) closed.insert(closed.end(), r.index_count / 3, r.closed ? 1 : 0);
    auto draw = [&](penumbra::CasterClass cls) {
        for (const auto& r : gpu.ranges()) {
            if (r.closed == (cls == penumbra::CasterClass::Closed)) gpu.draw(r);
        }
    };
    pipeline.run({gbuffer.positionBuffer().id(), gbuffer.faceBuffer().id()}, w * h, light, draw);  // warm-up
    t0 = std::chrono::steady_clock::now();
    const penumbra::AliasFreeHardFrame& frame = pipeline.run({gbuffer.positionBuffer().id(), gbuffer.faceBuffer().id()},
                                                             w * h, light, draw);
    glFinish();
    const double shadows_ms = msSince(t0);
    const std::vector<uint32_t> states = pipeline.stateBuffer().download<uint32_t>(0, size_t(w) * h);

    // --reference: the oracle's verdict on the same float samples and light point.
    size_t tested = 0, mismatched = 0, ties = 0, shadowed = 0;
    double reference_ms = 0;
    if (args.reference) {
        t0 = std::chrono::steady_clock::now();
        std::vector<glm::dvec3> receivers;
        std::vector<uint32_t> ids;
        for (uint32_t i = 0; i < states.size(); ++i) {
            if (states[i] != PENUMBRA_AFH_LIT && states[i] != PENUMBRA_AFH_SHADOWED) continue;
            receivers.emplace_back(glm::vec3(positions[i]));
            ids.push_back(i);
        }
        penumbra::reference::VisibilityOptions vo;
        vo.coplanar_epsilon = options.coplanar_epsilon;
        const auto result = oracle.evaluate(receivers, {glm::dvec3(glm::vec3(light.light))}, vo);
        tested = receivers.size();
        for (size_t r = 0; r < receivers.size(); ++r) {
            if (result.isTie(r, 0)) {
                ++ties;
                continue;
            }
            mismatched += (states[ids[r]] == PENUMBRA_AFH_SHADOWED) != result.isBlocked(r, 0);
        }
        reference_ms = msSince(t0);
    }

    // Shade: Lambert with the hard visibility; rows flipped (GL's bottom row first).
    t0 = std::chrono::steady_clock::now();
    penumbra::scene::ImageRgb8 image;
    image.width = w;
    image.height = h;
    image.pixels.assign(size_t(w) * h * 3, 0);
    const glm::vec3 albedo[2] = {{0.75f, 0.75f, 0.72f}, {0.85f, 0.45f, 0.2f}};
    for (uint32_t y = 0; y < h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            glm::vec3 c(0.08f, 0.09f, 0.12f);
            if (positions[i].w != 0.0f) {
                uint32_t triangle = 0;
                std::memcpy(&triangle, &faces[i].w, 4);
                const glm::vec3 n = glm::normalize(glm::vec3(shading[i * 4], shading[i * 4 + 1], shading[i * 4 + 2]));
                const glm::vec3 l = glm::normalize(glm::vec3(light_pos) - glm::vec3(positions[i]));
                const float lit = states[i] == PENUMBRA_AFH_LIT ? 1.0f : 0.0f;
                shadowed += states[i] == PENUMBRA_AFH_SHADOWED;
                c = albedo[triangle < material.size() ? material[triangle] : 1] *
                    (0.12f + 0.88f * std::max(0.0f, glm::dot(n, l)) * lit);
            }
            const size_t o = (size_t(h - 1 - y) * w + x) * 3;
            for (int k = 0; k < 3; ++k) image.pixels[o + k] = penumbra::scene::linearToSrgb8(c[k]);
        }
    }
    penumbra::scene::writePng(args.out, image);
    const double shade_ms = msSince(t0);
    const double total_ms = msSince(t_start);
    if (args.json) {
        std::printf(
            "{\"penumbra_version\":\"%d.%d.%d\",\"scene\":\"%s\",\"mode\":\"hard\",\"renderer\":\"%s\",\"width\":%u,"
            "\"height\":%u,\"triangles\":%zu,\"view_samples\":%zu,\"light_samples\":1,"
            "\"light\":{\"position\":[%.9g,%.9g,%.9g],\"radius\":0},"
            "\"hard\":{\"tested\":%zu,\"shadowed\":%zu,\"passes\":%u,\"max_list_length\":%u,\"occupancy\":%.6f,"
            "\"fragments\":%llu,\"tests\":%llu,\"triangles_emitted\":%llu}",
            penumbra::kVersionMajor, penumbra::kVersionMinor, penumbra::kVersionPatch, jsonEscape(args.scene).c_str(),
            jsonEscape(context.renderer()).c_str(), w, h, oracle.triangleCount(),
            view_samples, light_pos.x, light_pos.y, light_pos.z,
            static_cast<size_t>(frame.statistics.listed_samples), shadowed, frame.passes,
            frame.statistics.max_list_length, frame.statistics.occupancy(),
            static_cast<unsigned long long>(frame.fragments), static_cast<unsigned long long>(frame.tests),
            static_cast<unsigned long long>(frame.triangles_emitted));
        if (args.reference) {
            std::printf(",\"reference\":{\"samples\":%zu,\"mismatched\":%zu,\"ties\":%zu}", tested, mismatched, ties);
        }
        std::printf(",\"timings_ms\":{\"load\":%.3f,\"gbuffer\":%.3f,\"shadows\":%.3f,\"reference\":%.3f,"
                    "\"shade_and_write\":%.3f,\"total\":%.3f},\"out\":\"%s\"}\n",
                    load_ms, gbuffer_ms, shadows_ms, reference_ms, shade_ms, total_ms, jsonEscape(args.out).c_str());
    } else {
        std::printf("%s (hard, %s): %zu triangles, %zu samples tested, %zu shadowed, %.1f ms shadows -> %s\n",
                    args.scene.c_str(), context.renderer().c_str(), oracle.triangleCount(),
                    static_cast<size_t>(frame.statistics.listed_samples), shadowed, shadows_ms, args.out.c_str());
        if (args.reference) std::printf("reference: %zu mismatched, %zu ties of %zu\n", mismatched, ties, tested);
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    const Args args = parseArgs(argc, argv);
    const auto t_start = std::chrono::steady_clock::now();
    try {
        // ---- scene ----
        auto t0 = std::chrono::steady_clock::now();
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
            scene = penumbra::scene::loadObj(args.scene, options);
        }
        // Merge with a per-triangle material: mesh 0 is the ground when present.
        std::vector<glm::dvec3> positions;
        std::vector<glm::dvec3> normals;
        std::vector<uint32_t> indices;
        std::vector<uint8_t> material;
        for (const auto& mesh : scene.meshes) {
            const uint32_t base = static_cast<uint32_t>(positions.size());
            for (size_t v = 0; v < mesh.positions.size(); ++v) {
                positions.emplace_back(mesh.positions[v]);
                normals.emplace_back(v < mesh.normals.size() ? glm::dvec3(mesh.normals[v]) : glm::dvec3(0, 1, 0));
            }
            for (uint32_t idx : mesh.indices) indices.push_back(base + idx);
            material.insert(material.end(), mesh.indices.size() / 3, mesh.name == "ground" ? 0 : 1);
        }
        penumbra::reference::VisibilityOracle oracle(positions, indices);
        const double load_ms = msSince(t0);

        glm::dvec3 light_pos = args.has_light_pos ? args.light_pos : glm::dvec3(scene.light.position);
        double light_radius = args.light_radius >= 0 ? args.light_radius : scene.light.radius;
        if (args.mode == "hard") return runHard(args, scene, oracle, material, light_pos, load_ms, t_start);
        const std::vector<glm::dvec3> light_samples =
            penumbra::reference::sphereLightSamples(light_pos, light_radius, args.samples, 1);

        // ---- view samples: one primary ray per pixel ----
        t0 = std::chrono::steady_clock::now();
        const uint32_t w = args.width, h = args.height;
        const glm::dmat4 inv_view_proj = glm::inverse(glm::dmat4(scene.camera.projection(float(w) / float(h))) *
                                                      glm::dmat4(scene.camera.view()));
        std::vector<int64_t> pixel_sample(size_t(w) * h, -1);
        std::vector<glm::dvec3> hit_normal(size_t(w) * h);
        std::vector<uint32_t> hit_triangle(size_t(w) * h);
        std::vector<glm::dvec3> hit_point(size_t(w) * h);
        const glm::dvec3 eye(scene.camera.eye);
        parallelFor(size_t(w) * h, [&](size_t i) {
            const double x = (double(i % w) + 0.5) / w * 2.0 - 1.0;
            const double y = 1.0 - (double(i / w) + 0.5) / h * 2.0;  // row 0 is the top of the image
            glm::dvec4 far_point = inv_view_proj * glm::dvec4(x, y, 1.0, 1.0);
            glm::dvec3 dir = glm::normalize(glm::dvec3(far_point) / far_point.w - eye);
            penumbra::reference::Hit hit = oracle.closestHit(eye, dir, 0.0, 1e30);
            if (!hit.hit) return;
            const uint32_t* tri = &indices[size_t(hit.triangle) * 3];
            const double u = hit.u, v = hit.v;
            glm::dvec3 n = (1.0 - u - v) * normals[tri[0]] + u * normals[tri[1]] + v * normals[tri[2]];
            if (glm::dot(n, n) < 1e-20) {
                n = glm::cross(positions[tri[1]] - positions[tri[0]], positions[tri[2]] - positions[tri[0]]);
            }
            n = glm::normalize(n);
            if (glm::dot(n, dir) > 0) n = -n;  // open meshes: shade the side we see
            hit_point[i] = eye + hit.t * dir;
            hit_normal[i] = n;
            hit_triangle[i] = hit.triangle;
            pixel_sample[i] = 0;
        });
        std::vector<glm::dvec3> receivers;
        for (size_t i = 0; i < pixel_sample.size(); ++i) {
            if (pixel_sample[i] < 0) continue;
            pixel_sample[i] = static_cast<int64_t>(receivers.size());
            receivers.push_back(hit_point[i]);
        }
        const double primary_ms = msSince(t0);

        // ---- visibility: the exact oracle, every (view sample, light sample) pair ----
        t0 = std::chrono::steady_clock::now();
        penumbra::reference::VisibilityResult visibility = oracle.evaluate(receivers, light_samples);
        const double visibility_ms = msSince(t0);

        // ---- shade: Lambert with the sampled visibility, sRGB out ----
        t0 = std::chrono::steady_clock::now();
        penumbra::scene::ImageRgb8 image;
        image.width = w;
        image.height = h;
        image.pixels.assign(size_t(w) * h * 3, 0);
        const glm::dvec3 albedo[2] = {{0.75, 0.75, 0.72}, {0.85, 0.45, 0.2}};
        const glm::dvec3 sky(0.08, 0.09, 0.12);
        double lit_sum = 0;
        for (size_t i = 0; i < pixel_sample.size(); ++i) {
            glm::dvec3 c = sky;
            if (pixel_sample[i] >= 0) {
                const size_t r = static_cast<size_t>(pixel_sample[i]);
                const double vis = visibility.visibleFraction(r);
                lit_sum += vis;
                const glm::dvec3 l = glm::normalize(light_pos - hit_point[i]);
                const double ndotl = std::max(0.0, glm::dot(hit_normal[i], l));
                c = albedo[material[hit_triangle[i]]] * (0.12 + 0.88 * ndotl * vis);
            }
            for (int k = 0; k < 3; ++k) image.pixels[i * 3 + k] = penumbra::scene::linearToSrgb8(float(c[k]));
        }
        penumbra::scene::writePng(args.out, image);
        const double shade_ms = msSince(t0);

        const double total_ms = msSince(t_start);
        if (args.json) {
            std::printf(
                "{\"penumbra_version\":\"%d.%d.%d\",\"scene\":\"%s\",\"mode\":\"%s\",\"width\":%u,\"height\":%u,"
                "\"triangles\":%zu,\"view_samples\":%zu,\"light_samples\":%zu,"
                "\"light\":{\"position\":[%.9g,%.9g,%.9g],\"radius\":%.9g},"
                "\"mean_visible_fraction\":%.9g,\"reference\":{\"ties\":%llu,\"pairs\":%llu},"
                "\"timings_ms\":{\"load\":%.3f,\"view_samples\":%.3f,\"visibility\":%.3f,\"shade_and_write\":%.3f,"
                "\"total\":%.3f},\"out\":\"%s\"}\n",
                penumbra::kVersionMajor, penumbra::kVersionMinor, penumbra::kVersionPatch,
                jsonEscape(args.scene).c_str(), args.mode.c_str(), w, h, oracle.triangleCount(), receivers.size(),
                light_samples.size(), light_pos.x, light_pos.y, light_pos.z, light_radius,
                receivers.empty() ? 0.0 : lit_sum / double(receivers.size()),
                static_cast<unsigned long long>(visibility.tie_count),
                static_cast<unsigned long long>(receivers.size() * light_samples.size()), load_ms, primary_ms,
                visibility_ms, shade_ms, total_ms, jsonEscape(args.out).c_str());
        } else {
            std::printf("%s: %zu triangles, %zu view samples x %zu light samples, %.1f ms -> %s\n", args.scene.c_str(),
                        oracle.triangleCount(), receivers.size(), light_samples.size(), total_ms, args.out.c_str());
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "soft_shadows: %s\n", e.what());
        return 1;
    }
    return 0;
}
