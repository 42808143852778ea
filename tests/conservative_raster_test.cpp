// penumbra conservative raster (sintorn2008 §3.2, Fig. 4): the setup's validation, the exact
// predicate against hand-made boundary cases and an independent clipper, the CPU twin against the
// predicate, and the geometry-shader emitter on the real driver: >= 10^5 random triangles per
// variant (sub-pixel .. screen-size, 1e5-pixel vertices, slivers, collinear and coincident points,
// pixel-grid vertices touching pixel boundaries, near-plane crossings, random clip space, NaN/Inf)
// must miss 0 pixels the exact predicate requires, and the GPU's fragments must match the CPU
// twin's prediction up to pixels whose centre lies within the subpixel snap of the hull boundary
// (bitwise tier; on any driver: differences on <= 2% of the predicted pixels, none more than 1 px
// from the prediction).
// Coverage is recorded per triangle in a 32 x 32 tile bitset (PENUMBRA_CONSERVATIVE_RECORD), and
// the ground truth is computed from the clip coordinates the geometry stage itself recorded.
// Seeds are printed; PENUMBRA_SEED=<n> replays one. The `stress` suite runs 10^6 per variant.
#include <penumbra/conservative_raster.hpp>
#include <penumbra/gl/conservative_raster.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/shader.hpp>
#include <penumbra/shader_source.hpp>

#include "support/gl_test_support.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <array>
#include <bitset>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

using penumbra::ConservativeHullKind;
using penumbra::ConservativeRasterOptions;
using penumbra::ConservativeRasterSetup;
using penumbra::ConservativeVariant;
using penumbra::test::contains;
using penumbra::test::context;
using penumbra::test::errorOf;
using penumbra::test::testSeed;

double seconds(std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// max_triangles: the largest draw the test makes with this setup (sizes the Fixed-6 spill buffer).
ConservativeRasterSetup makeSetup(int x, int y, int w, int h, ConservativeVariant variant, int subpixel_bits = 8,
                                  bool drop = false, bool box = false, uint32_t max_triangles = 32768) {
    ConservativeRasterOptions o;
    o.viewport_x = x;
    o.viewport_y = y;
    o.viewport_width = w;
    o.viewport_height = h;
    o.variant = variant;
    o.subpixel_bits = subpixel_bits;
    o.drop_degenerate = drop;
    o.clip_to_box = box;
    o.max_triangles = max_triangles;
    return penumbra::conservativeRasterSetup(o);
}

std::string hexFloat(float f) {
    char buffer[48];
    std::snprintf(buffer, sizeof buffer, "%a", static_cast<double>(f));
    return buffer;
}

std::string describeClip(const glm::vec4 (&c)[3]) {
    std::ostringstream out;
    for (int i = 0; i < 3; ++i) {
        out << (i ? ", " : "") << "(" << hexFloat(c[i].x) << ", " << hexFloat(c[i].y) << ", " << hexFloat(c[i].z) << ", "
            << hexFloat(c[i].w) << ")";
    }
    return out.str();
}

// ---- random triangles ---------------------------------------------------------------------------

enum Category {
    kSubPixel,
    kSmall,
    kLarge,
    kHuge,
    kSliver,
    kCollinear,
    kCoincident,
    kGrid,
    kNearPlane,
    kRandomClip,
    kNonFinite,
    kCategoryCount
};

const char* categoryName(int c) {
    static const char* names[] = {"sub-pixel", "small", "screen-size", "1e5-px vertices", "sliver", "collinear",
                                  "coincident", "pixel-grid", "near-plane", "random clip", "NaN/Inf"};
    return names[c];
}

struct TestTriangle {
    glm::vec4 v[3];
    int category = 0;
};

// Triangles in clip space for a width x height viewport (pixel coordinates are viewport-relative).
class TriangleGenerator {
public:
    TriangleGenerator(uint32_t seed, int width, int height) : rng_(seed), width_(width), height_(height) {
        const double weights[kCategoryCount] = {14, 14, 14, 8, 10, 6, 4, 10, 9, 8, 3};
        double total = 0;
        for (double w : weights) total += w;
        double running = 0;
        for (int i = 0; i < kCategoryCount; ++i) cumulative_[i] = (running += weights[i]) / total;
    }

    TestTriangle next() {
        const double u = uniform(0, 1);
        int category = 0;
        while (category + 1 < kCategoryCount && u > cumulative_[category]) ++category;
        return make(category);
    }

    TestTriangle make(int category) {
        TestTriangle t;
        t.category = category;
        const glm::vec2 size(width_, height_);
        switch (category) {
            case kSubPixel:
            case kSmall:
            case kLarge:
            case kNonFinite: {
                const double lo = category == kSubPixel ? -3 : category == kLarge ? 0.9 : 0;
                const double hi = category == kSubPixel ? 0 : category == kLarge ? 2.2 : 0.9;
                const double s = std::pow(10.0, uniform(lo, hi));
                const glm::dvec2 c = category == kLarge ? glm::dvec2(uniform(-0.5, 1.5) * size.x, uniform(-0.5, 1.5) * size.y)
                                                        : glm::dvec2(uniform(-2, size.x + 2), uniform(-2, size.y + 2));
                for (auto& v : t.v) v = fromPixels(c + s * glm::dvec2(uniform(-1, 1), uniform(-1, 1)));
                if (category == kNonFinite) {
                    const float bad[3] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                                          -std::numeric_limits<float>::infinity()};
                    t.v[rng_() % 3][static_cast<int>(rng_() % 4)] = bad[rng_() % 3];
                }
                break;
            }
            case kHuge: {  // a line through the viewport with endpoints 1e2..1e5 pixels away
                const glm::dvec2 q(uniform(0, size.x), uniform(0, size.y));
                const double angle = uniform(0, 6.283185307179586);
                const glm::dvec2 dir(std::cos(angle), std::sin(angle)), perp(-dir.y, dir.x);
                const glm::dvec2 a = q + std::pow(10.0, uniform(2, 5)) * dir;
                const glm::dvec2 b = q - std::pow(10.0, uniform(2, 5)) * dir;
                const glm::dvec2 c = q + (rng_() % 2 ? 1.0 : -1.0) * std::pow(10.0, uniform(-1, 5)) * perp +
                                     uniform(-1, 1) * std::pow(10.0, uniform(0, 5)) * dir;
                t.v[0] = fromPixels(a);
                t.v[1] = fromPixels(b);
                t.v[2] = fromPixels(c);
                break;
            }
            case kSliver:
            case kCollinear: {
                const glm::dvec2 a(uniform(-4, size.x + 4), uniform(-4, size.y + 4));
                const double angle = uniform(0, 6.283185307179586);
                glm::dvec2 b = a + std::pow(10.0, uniform(-1, 2.3)) * glm::dvec2(std::cos(angle), std::sin(angle));
                const double s = uniform(-0.2, 1.2);
                glm::dvec2 c = a + s * (b - a);
                if (category == kSliver) {
                    const glm::dvec2 d = glm::normalize(b - a);
                    c += (rng_() % 2 ? 1.0 : -1.0) * std::pow(10.0, uniform(-7, -1)) * glm::dvec2(-d.y, d.x);
                } else if (rng_() % 3 == 0) {  // exactly collinear: axis-aligned
                    if (rng_() % 2) b.y = c.y = a.y;
                    else b.x = c.x = a.x;
                }
                t.v[0] = fromPixels(a);
                t.v[1] = fromPixels(b);
                t.v[2] = fromPixels(c);
                break;
            }
            case kCoincident: {
                const glm::dvec2 a(uniform(-2, size.x + 2), uniform(-2, size.y + 2));
                const glm::dvec2 b = a + std::pow(10.0, uniform(-2, 1.5)) * glm::dvec2(uniform(-1, 1), uniform(-1, 1));
                const glm::vec4 va = fromPixels(a), vb = fromPixels(b);
                switch (rng_() % 4) {
                    case 0: t.v[0] = va, t.v[1] = va, t.v[2] = vb; break;
                    case 1: t.v[0] = va, t.v[1] = vb, t.v[2] = va; break;
                    case 2: t.v[0] = vb, t.v[1] = va, t.v[2] = va; break;
                    default: t.v[0] = va, t.v[1] = va, t.v[2] = va; break;
                }
                break;
            }
            case kGrid: {  // vertices on the half-pixel grid, w = 1: exact, boundaries touched
                const int span = rng_() % 2 ? 12 : 2 * std::max(width_, height_) + 8;
                const int bx = static_cast<int>(rng_() % static_cast<uint32_t>(2 * width_ + 8)) - 4;
                const int by = static_cast<int>(rng_() % static_cast<uint32_t>(2 * height_ + 8)) - 4;
                for (auto& v : t.v) {
                    const int kx = bx + static_cast<int>(rng_() % static_cast<uint32_t>(span)) - span / 2;
                    const int ky = by + static_cast<int>(rng_() % static_cast<uint32_t>(span)) - span / 2;
                    v = glm::vec4(static_cast<float>(kx) / static_cast<float>(width_) - 1.0f,
                                  static_cast<float>(ky) / static_cast<float>(height_) - 1.0f, 0.0f, 1.0f);
                }
                if (rng_() % 4 == 0) t.v[2] = t.v[rng_() % 2];  // degenerate: a point or a grid-aligned segment
                break;
            }
            case kNearPlane: {  // eye space through a float perspective: many cross z = -w
                const float fovy = static_cast<float>(uniform(0.5, 1.8));
                const glm::mat4 projection = glm::perspective(fovy, size.x / size.y, 0.1f, 100.0f);
                for (auto& v : t.v) {
                    const glm::vec4 eye(static_cast<float>(uniform(-2, 2)), static_cast<float>(uniform(-2, 2)),
                                        static_cast<float>(uniform(-3, 0.5)), 1.0f);
                    v = projection * eye;
                }
                break;
            }
            default: {  // random clip space: w of any sign, z anywhere
                for (auto& v : t.v) {
                    v = glm::vec4(static_cast<float>(uniform(-3, 3)), static_cast<float>(uniform(-3, 3)),
                                  static_cast<float>(uniform(-3, 3)), static_cast<float>(uniform(-1, 3)));
                }
                break;
            }
        }
        if (rng_() % 2) std::swap(t.v[1], t.v[2]);  // either winding
        return t;
    }

    double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }

    // Pixel coordinates (viewport-relative) -> clip space with a random w and depth.
    glm::vec4 fromPixels(glm::dvec2 p) {
        const double w = std::pow(10.0, uniform(-0.6, 0.6));
        const double z = uniform(-0.95, 0.95);
        return glm::vec4(static_cast<float>((p.x / width_ * 2.0 - 1.0) * w), static_cast<float>((p.y / height_ * 2.0 - 1.0) * w),
                         static_cast<float>(z * w), static_cast<float>(w));
    }

private:
    std::mt19937 rng_;
    int width_, height_;
    double cumulative_[kCategoryCount];
};

// ---- checking one triangle's coverage -----------------------------------------------------------

constexpr int kTile = PENUMBRA_CONSERVATIVE_RECORD_TILE;
constexpr int kConservativeFixed6MaxVertices = penumbra::kConservativeFixed6MaxVertices;
constexpr int kWords = PENUMBRA_CONSERVATIVE_RECORD_WORDS;

struct CoverageStats {
    uint64_t triangles = 0, required = 0, covered = 0, fragments = 0, missed = 0, missed_triangles = 0;
    uint64_t extra = 0, max_extra = 0, unchecked = 0, outside = 0, duplicates = 0;
    uint64_t predicted_but_absent = 0, present_but_unpredicted = 0, uncertain = 0;
    // The twin's predicted fragments (certain, in the tile), and the GPU's unpredicted fragments
    // more than 1 pixel (Chebyshev) from every pixel the twin predicts or leaves uncertain.
    uint64_t predicted = 0, unpredicted_far = 0;
    uint64_t nonfinite_with_fragments = 0, record_mismatches = 0;
    // Fixed-6 two-pass plan: triangles the CPU predicate says the direct pass spills, what the GPU's
    // spill header reports (count / 3 + overflow), and overflows; hulls over 6 vertices outside it.
    uint64_t spill_predicted = 0, spill_gpu = 0, spill_overflow = 0, direct_over_six = 0, twin_spill_disagreements = 0;
    bool two_pass = false;
    uint64_t kinds[6] = {};
    uint64_t category_triangles[kCategoryCount] = {}, category_extra[kCategoryCount] = {},
             category_required[kCategoryCount] = {};
    std::vector<std::string> failures;

    void merge(const CoverageStats& o) {
        triangles += o.triangles, required += o.required, covered += o.covered, fragments += o.fragments;
        missed += o.missed, missed_triangles += o.missed_triangles, extra += o.extra;
        max_extra = std::max(max_extra, o.max_extra), unchecked += o.unchecked, outside += o.outside;
        duplicates += o.duplicates, predicted_but_absent += o.predicted_but_absent;
        present_but_unpredicted += o.present_but_unpredicted, uncertain += o.uncertain;
        predicted += o.predicted, unpredicted_far += o.unpredicted_far;
        nonfinite_with_fragments += o.nonfinite_with_fragments, record_mismatches += o.record_mismatches;
        spill_predicted += o.spill_predicted, spill_gpu += o.spill_gpu, spill_overflow += o.spill_overflow;
        direct_over_six += o.direct_over_six, twin_spill_disagreements += o.twin_spill_disagreements;
        two_pass = two_pass || o.two_pass;
        for (int i = 0; i < 6; ++i) kinds[i] += o.kinds[i];
        for (int i = 0; i < kCategoryCount; ++i) {
            category_triangles[i] += o.category_triangles[i];
            category_extra[i] += o.category_extra[i];
            category_required[i] += o.category_required[i];
        }
        for (const auto& f : o.failures) {
            if (failures.size() < 8) failures.push_back(f);
        }
    }

    std::string summary(const std::string& label, uint32_t seed) const {
        std::ostringstream out;
        out.setf(std::ios::fixed);
        out.precision(3);
        const double t = static_cast<double>(std::max<uint64_t>(triangles, 1));
        out << label << ": " << triangles << " triangles (seed " << seed << "): " << required
            << " required pixels, missed " << missed << "; over-coverage " << static_cast<double>(extra) / t
            << " extra pixels/triangle (max " << max_extra << "), ratio extra/required "
            << static_cast<double>(extra) / static_cast<double>(std::max<uint64_t>(required, 1))
            << "; fragments/triangle " << static_cast<double>(fragments) / t << "; GPU vs CPU-twin raster: "
            << predicted_but_absent << " predicted-but-absent, " << present_but_unpredicted
            << " unpredicted (" << unpredicted_far << " more than 1 px from the prediction) of " << predicted
            << " predicted, " << uncertain << " pixels within the snap tolerance; duplicate fragments "
            << duplicates << "; hull kinds dropped/culled/triangle/clipped/thin/fallback = " << kinds[0] << "/"
            << kinds[1] << "/" << kinds[2] << "/" << kinds[3] << "/" << kinds[4] << "/" << kinds[5];
        if (two_pass) {
            out << "\n  two-pass plan: direct pass at max_vertices 6, spilled " << spill_gpu << " triangles (GPU header; CPU predicate "
                << spill_predicted << ", overflow " << spill_overflow << "), spill fraction "
                << static_cast<double>(spill_gpu) / t;
        } else {
            out << "\n  single pass at max_vertices " << PENUMBRA_CONSERVATIVE_MAX_VERTICES << " (the spill predicate holds for "
                << spill_predicted << " triangles, fraction " << static_cast<double>(spill_predicted) / t << ")";
        }
        out << "\n  per category (triangles, extra/triangle, extra/required):";
        for (int c = 0; c < kCategoryCount; ++c) {
            if (!category_triangles[c]) continue;
            out << "\n    " << categoryName(c) << ": " << category_triangles[c] << ", "
                << static_cast<double>(category_extra[c]) / static_cast<double>(category_triangles[c]) << ", "
                << static_cast<double>(category_extra[c]) / static_cast<double>(std::max<uint64_t>(category_required[c], 1));
        }
        return out.str();
    }
};

// Snap tolerance for comparing the GPU with the twin's prediction: GL moves each hull vertex by up
// to half a subpixel (2^-9 px at 8 bits) and the GPU's float hull differs from the twin's by a few
// ulps; 1/64 px is comfortably more than both.
constexpr double kPredictionTolerance = 1.0 / 64.0;

// Checks one triangle: `words` are its kWords recorded words, `tile` its tile origin (window).
void checkTriangle(const ConservativeRasterSetup& setup, const glm::vec4 (&clip)[3], const uint32_t* words,
                   glm::ivec2 tile, int category, CoverageStats& stats) {
    stats.triangles++;
    stats.category_triangles[category]++;
    const glm::ivec2 tile_rel = tile - glm::ivec2(setup.options.viewport_x, setup.options.viewport_y);
    auto bit = [&](glm::ivec2 p, bool* checked) {
        const glm::ivec2 l = p - tile_rel;
        *checked = l.x >= 0 && l.y >= 0 && l.x < kTile && l.y < kTile;
        return *checked && ((words[l.y] >> l.x) & 1u) != 0;
    };
    uint64_t covered = 0;
    for (int r = 0; r < kTile; ++r) covered += static_cast<uint64_t>(std::bitset<32>(words[r]).count());
    const uint64_t fragments = words[PENUMBRA_CONSERVATIVE_RECORD_FRAGMENTS];
    const uint64_t outside = words[PENUMBRA_CONSERVATIVE_RECORD_OUTSIDE];
    stats.covered += covered;
    stats.fragments += fragments;
    stats.outside += outside;
    if (fragments > covered + outside) stats.duplicates += fragments - covered - outside;

    const std::vector<glm::ivec2> required = penumbra::conservativeRequiredPixels(clip[0], clip[1], clip[2], setup);
    uint64_t missed = 0, required_in_tile = 0;
    glm::ivec2 first_missed(-1);
    for (const auto& p : required) {
        bool checked = false;
        const bool set = bit(p, &checked);
        if (!checked) {
            stats.unchecked++;
            continue;
        }
        required_in_tile++;
        if (!set) {
            if (!missed) first_missed = p;
            ++missed;
        }
    }
    stats.required += required.size();
    stats.category_required[category] += required.size();
    const penumbra::ConservativeHull hull = penumbra::conservativeHull(clip, setup);
    stats.kinds[static_cast<int>(hull.kind)]++;
    const bool needs_spill = penumbra::conservativeNeedsSpill(clip[0], clip[1], clip[2], setup);
    stats.spill_predicted += needs_spill;
    if (setup.spill.enabled && (hull.spilled != needs_spill) && stats.failures.size() < 8) {
        stats.failures.push_back("twin's hull.spilled disagrees with conservativeNeedsSpill: " + describeClip(clip));
    }
    if (setup.spill.enabled) stats.twin_spill_disagreements += hull.spilled != needs_spill;
    // What the direct pass emits must fit its declared 6 vertices.
    if (setup.options.variant == ConservativeVariant::Fixed6 && !needs_spill && hull.count > kConservativeFixed6MaxVertices) {
        stats.direct_over_six++;
    }
    // drop_degenerate: the contract lets thin triangles go (whether the GPU's float threshold test
    // agrees with the twin's on a borderline one is irrelevant), so only the others must cover.
    if (setup.options.drop_degenerate && hull.kind == ConservativeHullKind::Dropped) missed = 0;
    stats.missed += missed;
    if (missed) {
        stats.missed_triangles++;
        if (stats.failures.size() < 8) {
            std::ostringstream out;
            out << "missed " << missed << " pixel(s), first (" << first_missed.x << ", " << first_missed.y << "), "
                << categoryName(category) << " triangle, hull kind " << static_cast<int>(hull.kind) << " with "
                << hull.count << " vertices, clip " << describeClip(clip);
            stats.failures.push_back(out.str());
        }
    }
    const uint64_t extra = covered > required_in_tile ? covered - required_in_tile : 0;
    stats.extra += extra + outside;
    stats.category_extra[category] += extra + outside;
    stats.max_extra = std::max(stats.max_extra, extra + outside);
    if (category == kNonFinite && fragments) {
        stats.nonfinite_with_fragments++;
        if (stats.failures.size() < 8) stats.failures.push_back("NaN/Inf triangle produced fragments: " + describeClip(clip));
    }

    // The GPU against the twin's prediction: certain pixels present, nothing outside certain+uncertain.
    const penumbra::HullRaster raster = penumbra::rasterizeConservativeHull(hull, setup, kPredictionTolerance);
    std::array<uint32_t, kTile> allowed{};
    for (const auto& p : raster.fragments) {
        bool checked = false;
        const bool set = bit(p, &checked);
        if (!checked) continue;
        allowed[static_cast<size_t>(p.y - tile_rel.y)] |= 1u << (p.x - tile_rel.x);
        stats.predicted++;
        if (!set) stats.predicted_but_absent++;
    }
    for (const auto& p : raster.uncertain) {
        bool checked = false;
        bit(p, &checked);
        if (checked) allowed[static_cast<size_t>(p.y - tile_rel.y)] |= 1u << (p.x - tile_rel.x);
    }
    stats.uncertain += raster.uncertain.size();
    // `near`: the allowed pixels dilated by one pixel in x, y and diagonally (Chebyshev distance 1).
    std::array<uint32_t, kTile> near{};
    for (int r = 0; r < kTile; ++r) {
        const uint32_t row = allowed[static_cast<size_t>(r)];
        const uint32_t wide = row | (row << 1) | (row >> 1);
        near[static_cast<size_t>(r)] |= wide;
        if (r > 0) near[static_cast<size_t>(r - 1)] |= wide;
        if (r + 1 < kTile) near[static_cast<size_t>(r + 1)] |= wide;
    }
    uint64_t unpredicted = 0, far = 0;
    for (int r = 0; r < kTile; ++r) {
        unpredicted += std::bitset<32>(words[r] & ~allowed[static_cast<size_t>(r)]).count();
        far += std::bitset<32>(words[r] & ~near[static_cast<size_t>(r)]).count();
    }
    stats.present_but_unpredicted += unpredicted;
    stats.unpredicted_far += far;
    // Far ones fail the portable tier; keep room for them among the first failures.
    if (far && stats.failures.size() < 8) {
        stats.failures.push_back("GPU fragments more than 1 px from the twin's prediction: " + std::to_string(far) + " in " +
                                 categoryName(category) + " triangle " + describeClip(clip));
    } else if (unpredicted && stats.failures.size() < 4) {
        stats.failures.push_back("GPU fragments the twin does not predict: " + std::to_string(unpredicted) + " in " +
                                 categoryName(category) + " triangle " + describeClip(clip));
    }
}

// Checks triangles [0, n) on two threads.
CoverageStats checkAll(const ConservativeRasterSetup& setup, const std::vector<TestTriangle>& triangles,
                       const std::vector<glm::vec4>& clips, const std::vector<uint32_t>& words,
                       const std::vector<glm::ivec2>& tiles) {
    const size_t n = triangles.size();
    const unsigned thread_count = std::max(1u, std::min(4u, std::thread::hardware_concurrency()));
    std::vector<CoverageStats> partial(thread_count);
    std::vector<std::thread> threads;
    for (unsigned t = 0; t < thread_count; ++t) {
        threads.emplace_back([&, t] {
            for (size_t i = t; i < n; i += thread_count) {
                const glm::vec4 clip[3] = {clips[3 * i], clips[3 * i + 1], clips[3 * i + 2]};
                checkTriangle(setup, clip, &words[i * kWords], tiles[i], triangles[i].category, partial[t]);
            }
        });
    }
    for (auto& th : threads) th.join();
    CoverageStats total;
    for (const auto& p : partial) total.merge(p);
    return total;
}

// ---- GL harness ---------------------------------------------------------------------------------

int subpixelBits() { return penumbra::gl::getInteger(GL_SUBPIXEL_BITS); }

// How the test draws: the Fixed-6 two-pass plan (direct pass at max_vertices 6 + spill pass), or
// the single-pass emitter (max_vertices 13; what the hard-shadow light pass includes).
enum class Passes { Plan, Single };

struct Recorded {
    std::vector<uint32_t> words;
    std::vector<glm::vec4> clips;
    penumbra::ConservativeSpillHeader spill{};  ///< after the direct pass (two-pass plan only)
    bool two_pass = false;
};

constexpr const char* kVert = "penumbra/conservative_raster/conservative_raster.vert.glsl";
constexpr const char* kGeom = "penumbra/conservative_raster/conservative_raster.geom.glsl";
constexpr const char* kFrag = "penumbra/conservative_raster/conservative_raster.frag.glsl";

// Programs keyed by their define set.
penumbra::gl::Program& program(const penumbra::ShaderDefines& base, bool transform, bool record = true) {
    static std::map<std::string, std::unique_ptr<penumbra::gl::Program>> cache;
    penumbra::ShaderDefines defines = base;
    defines.push_back({"PENUMBRA_CONSERVATIVE_RECORD", record ? "1" : "0"});
    defines.push_back({"PENUMBRA_CONSERVATIVE_VS_TRANSFORM", transform ? "1" : "0"});
    std::string key;
    for (const auto& d : defines) key += d.name + "=" + d.value + ";";
    auto& slot = cache[key];
    if (!slot) slot = std::make_unique<penumbra::gl::Program>(penumbra::gl::buildProgram({kVert, kGeom, kFrag}, defines));
    return *slot;
}

// Draws the triangles (3 vertices each) in one call into a framebuffer with no attachments of
// `fb_size`, recording coverage per triangle. `matrix` non-null: vertices are world positions.
// Passes::Plan with a Fixed6 setup runs the setup's two-pass plan exactly as an engine would:
// reset the spill header, direct draw, barrier, indirect spill draw (no vertex attributes).
// `spill_capacity` non-zero overrides the plan's capacity (to provoke overflow).
Recorded record(const ConservativeRasterSetup& setup, glm::ivec2 fb_size, const std::vector<glm::vec4>& vertices,
                const std::vector<glm::ivec2>& tiles, const glm::mat4* matrix = nullptr, Passes passes = Passes::Plan,
                uint32_t spill_capacity = 0) {
    const size_t n = tiles.size();
    REQUIRE(vertices.size() == 3 * n);
    Recorded out;
    out.two_pass = passes == Passes::Plan && setup.spill.enabled;
    if (n == 0) return out;
    auto vbo = penumbra::gl::Buffer::fromVector(vertices);
    auto tile_buffer = penumbra::gl::Buffer::fromVector(tiles);
    penumbra::gl::Buffer words(n * kWords * sizeof(uint32_t));
    penumbra::gl::Buffer clips(3 * n * sizeof(glm::vec4));
    words.fill(0u);              // the recorder ORs and adds into it
    clips.fill(0xffffffffu);     // poison: every triangle's record must be overwritten
    penumbra::gl::Buffer params(sizeof(setup.params), &setup.params);
    // The plan's spill buffer, sized by the setup (every triangle of this draw fits: max_triangles),
    // at a non-zero offset inside a larger buffer, as an engine's sub-allocation would be.
    ConservativeRasterSetup plan = setup;
    if (spill_capacity) {
        plan.spill.capacity = plan.spill.reset.capacity = spill_capacity;
        plan.spill.buffer_bytes = plan.spill.triangles_offset + uint64_t(spill_capacity) * plan.spill.triangle_bytes;
    }
    const uint64_t spill_offset = 256;
    penumbra::gl::Buffer spill(static_cast<size_t>(spill_offset + (out.two_pass ? plan.spill.buffer_bytes : 64) + 64));
    spill.fill(0xffffffffu);  // poison the header and the triangle array
    const penumbra::BufferRange spill_range{spill.id(), spill_offset, out.two_pass ? plan.spill.buffer_bytes : 0};
    if (out.two_pass) {
        penumbra::gl::validateConservativeSpill(plan, spill_range);
        REQUIRE(penumbra::gl::beginConservativeSpill(plan, spill_range) == penumbra::Status::Ok);
    }

    GLuint vao = 0, empty_vao = 0, fbo = 0;
    glCreateVertexArrays(1, &vao);
    glCreateVertexArrays(1, &empty_vao);
    glVertexArrayVertexBuffer(vao, 0, vbo.id(), 0, sizeof(glm::vec4));
    glVertexArrayAttribFormat(vao, 0, 4, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(vao, 0, 0);
    glEnableVertexArrayAttrib(vao, 0);
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferParameteri(fbo, GL_FRAMEBUFFER_DEFAULT_WIDTH, fb_size.x);
    glNamedFramebufferParameteri(fbo, GL_FRAMEBUFFER_DEFAULT_HEIGHT, fb_size.y);
    REQUIRE(glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE);

    penumbra::gl::Program& p = program(out.two_pass ? setup.spill.direct_defines : setup.defines, matrix != nullptr);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(setup.options.viewport_x, setup.options.viewport_y, setup.width(), setup.height());
    glDisable(GL_CULL_FACE);
    glDisable(GL_DEPTH_TEST);
    glBindVertexArray(vao);
    p.use();
    glUniform1ui(8, 0u);
    if (matrix) glUniformMatrix4fv(0, 1, GL_FALSE, &(*matrix)[0][0]);
    glBindBufferBase(GL_UNIFORM_BUFFER, PENUMBRA_CONSERVATIVE_PARAMS_BINDING, params.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_CONSERVATIVE_RECORD_WORDS_BINDING, words.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_CONSERVATIVE_RECORD_TILES_BINDING, tile_buffer.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_CONSERVATIVE_RECORD_CLIP_BINDING, clips.id());
    glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(3 * n));
    if (out.two_pass) {
        penumbra::gl::Program& q = program(setup.spill.spill_defines, false);
        q.use();
        glBindVertexArray(empty_vao);
        REQUIRE(penumbra::gl::drawConservativeSpill(plan, spill_range) == penumbra::Status::Ok);
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
    }
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    out.words = words.download<uint32_t>();
    out.clips = clips.download<glm::vec4>();
    if (out.two_pass) out.spill = penumbra::gl::readConservativeSpillHeader(spill_range);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glBindVertexArray(0);
    glDeleteFramebuffers(1, &fbo);
    glDeleteVertexArrays(1, &vao);
    glDeleteVertexArrays(1, &empty_vao);
    penumbra::gl::checkErrors("conservative raster record");
    return out;
}

// The GPU's spill report against the CPU predicate over the recorded triangles.
void addSpill(const Recorded& rec, CoverageStats& stats) {
    stats.two_pass = stats.two_pass || rec.two_pass;
    if (!rec.two_pass) return;
    stats.spill_gpu += rec.spill.count / 3u + rec.spill.overflow;
    stats.spill_overflow += rec.spill.overflow;
}

bool sameBits(const glm::vec4& a, const glm::vec4& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Generates `count` triangles in batches for one viewport, renders and checks them.
CoverageStats runRandom(ConservativeVariant variant, uint32_t seed, size_t count, glm::ivec4 viewport,
                        glm::ivec2 fb_size, bool clip_to_box = false, Passes passes = Passes::Plan) {
    const ConservativeRasterSetup setup =
        makeSetup(viewport.x, viewport.y, viewport.z, viewport.w, variant, subpixelBits(), false, clip_to_box);
    TriangleGenerator generator(seed, viewport.z, viewport.w);
    CoverageStats total;
    const size_t batch = 32768;
    for (size_t done = 0; done < count; done += batch) {
        const size_t n = std::min(batch, count - done);
        std::vector<TestTriangle> triangles(n);
        std::vector<glm::vec4> vertices;
        vertices.reserve(3 * n);
        for (auto& t : triangles) {
            t = generator.next();
            vertices.insert(vertices.end(), t.v, t.v + 3);
        }
        const std::vector<glm::ivec2> tiles(n, glm::ivec2(viewport.x, viewport.y));
        const Recorded rec = record(setup, fb_size, vertices, tiles, nullptr, passes);
        CoverageStats stats = checkAll(setup, triangles, rec.clips, rec.words, tiles);
        addSpill(rec, stats);
        for (size_t i = 0; i < 3 * n; ++i) stats.record_mismatches += !sameBits(rec.clips[i], vertices[i]);
        total.merge(stats);
    }
    return total;
}

void requireClean(const CoverageStats& s, bool expect_prediction = true) {
    std::string failures;
    for (const auto& f : s.failures) failures += "\n  " + f;
    INFO("first failures:", failures);
    CHECK(s.missed == 0);
    CHECK(s.nonfinite_with_fragments == 0);
    CHECK(s.record_mismatches == 0);
    CHECK(s.unchecked == 0);
    CHECK(s.outside == 0);
    CHECK(s.kinds[static_cast<int>(ConservativeHullKind::Fallback)] == 0);
    CHECK(s.direct_over_six == 0);
    CHECK(s.twin_spill_disagreements == 0);
    if (s.two_pass) {
        // Every triangle the CPU predicate spills, and no other, went through the spill buffer (a
        // float decision: bit for bit where floats round correctly; elsewhere borderline triangles
        // may go either way, at most 1%, and coverage is checked per pixel above either way).
        PENUMBRA_CHECK_BITWISE("conservative raster: GPU spills exactly the triangles the CPU predicate spills",
                               s.spill_gpu == s.spill_predicted);
        CHECK((s.spill_gpu > s.spill_predicted ? s.spill_gpu - s.spill_predicted : s.spill_predicted - s.spill_gpu) * 100 <=
              s.spill_predicted + 100);
        CHECK(s.spill_overflow == 0);
    }
    if (expect_prediction) {
        // Which pixels the GPU emits, outside the snap tolerance, is a float-exact property: the
        // geometry stage builds the expanded polygon with float operations a driver may fuse (a*b+c)
        // or round within GLSL's ulps (the perspective divide, the case-iii normalisation), and
        // hardware decides pixel centres exactly on an edge by its own snapped edge functions.
        PENUMBRA_CHECK_BITWISE("conservative raster: every fragment the CPU twin predicts is emitted",
                               s.predicted_but_absent == 0);
        PENUMBRA_CHECK_BITWISE("conservative raster: the GPU emits no fragment the CPU twin does not predict",
                               s.present_but_unpredicted == 0);
        // Portable: conservativeness is `missed == 0` above (the exact double-precision predicate).
        // The rest is bounded. Rounding alone moves the GPU's hull vertices by a few ulps of the
        // window coordinate (2^-9 px per ulp at 16384 px), far inside kPredictionTolerance, so it
        // only flips pixels the twin already calls uncertain. What moves pixels beyond that are the
        // discrete decisions the emitter takes on those floats: an edge direction within rounding
        // of an axis picks the neighbouring corner of the dilation square, so a Fixed-6 corner gains
        // or loses its case-iii extension (2h ~ 1 px past the corner, which over-covers by at most
        // one pixel: sintorn2008 §3.2), and the thin test on an area at its threshold swaps the
        // hexagon for the thin hull (both contain the triangle dilated by h; they differ by the
        // thickness, << 1 px, and by case-iii corners). Either way an extra fragment lies within 1
        // pixel (Chebyshev) of a pixel the twin predicts or leaves uncertain, and the differences
        // are rare: the H200 (driver 580.159) differed on 743 pixels of 127 740 predicted (0.58%)
        // in the 16384^2 Fixed-6 run, its worst case (sub-pixel triangles), and on 0 elsewhere.
        CHECK(s.unpredicted_far == 0);
        CHECK((s.predicted_but_absent + s.present_but_unpredicted) * 100 <= 2 * s.predicted);
    }
}

size_t defaultCount(size_t normal) {
    return static_cast<size_t>(penumbra::test::envCount("PENUMBRA_CONSERVATIVE_TRIANGLES", static_cast<long>(normal)));
}

}  // namespace

// ---- CPU: setup ---------------------------------------------------------------------------------

TEST_CASE("cpu: setup validates every option and names the bad value") {
    ConservativeRasterOptions o;
    CHECK(contains(errorOf([&] { penumbra::conservativeRasterSetup(o); }), "viewport_width = 0"));
    o.viewport_width = 64;
    CHECK(contains(errorOf([&] { penumbra::conservativeRasterSetup(o); }), "viewport_height = 0"));
    o.viewport_height = -3;
    CHECK(contains(errorOf([&] { penumbra::conservativeRasterSetup(o); }), "viewport_height = -3"));
    o.viewport_height = 40000;
    CHECK(contains(errorOf([&] { penumbra::conservativeRasterSetup(o); }), "viewport_height = 40000"));
    o.viewport_height = 48;
    CHECK_NOTHROW(penumbra::conservativeRasterSetup(o));
    auto bad = [&](auto mutate, const char* name) {
        ConservativeRasterOptions b = o;
        mutate(b);
        const std::string e = errorOf([&] { penumbra::conservativeRasterSetup(b); });
        INFO(e);
        CHECK(contains(e, name));
    };
    bad([](auto& b) { b.viewport_x = 1 << 20; }, "viewport origin");
    bad([](auto& b) { b.subpixel_bits = 0; }, "subpixel_bits = 0");
    bad([](auto& b) { b.subpixel_bits = 17; }, "subpixel_bits = 17");
    bad([](auto& b) { b.extra_margin = -1.0f; }, "extra_margin = -1");
    bad([](auto& b) { b.extra_margin = std::numeric_limits<float>::quiet_NaN(); }, "extra_margin = nan");
    bad([](auto& b) { b.guard_band = 0.5f; }, "guard_band = 0.5");
    bad([](auto& b) { b.min_w = 0.0f; }, "min_w = 0");
    bad([](auto& b) { b.near_plane = glm::vec4(1, 0, 0, 0); }, "near_plane = (1, 0, 0, 0)");
    bad([](auto& b) { b.near_plane.z = std::numeric_limits<float>::infinity(); }, "near_plane");
    bad([](auto& b) { b.variant = static_cast<ConservativeVariant>(7); }, "variant = 7");
    bad([](auto& b) { b.depth_clip_range = glm::vec2(0, 0); }, "depth_clip_range = (0, 0)");
    bad([](auto& b) { b.depth_clip_range = glm::vec2(-2, 1); }, "depth_clip_range = (-2, 1)");
    bad([](auto& b) { b.spill_capacity = penumbra::kConservativeMaxSpillCapacity + 1; }, "spill_capacity = 16777217");
    bad([](auto& b) { b.max_triangles = 1u << 30; }, "max_triangles = 1073741824");
    {
        // The Fixed-6 plan: sized from max_triangles (never overflows), else spill_capacity, else the default.
        ConservativeRasterOptions f = o;
        CHECK(penumbra::conservativeRasterSetup(f).spill.capacity == penumbra::kConservativeDefaultSpillCapacity);
        f.max_triangles = 5000;
        const ConservativeRasterSetup fs = penumbra::conservativeRasterSetup(f);
        CHECK(fs.spill.enabled);
        CHECK(fs.spill.capacity == 5000u);
        CHECK(fs.spill.buffer_bytes == 32u + 64u * 5000u);
        CHECK(fs.spill.triangles_offset == 32u);
        CHECK(fs.spill.indirect_offset == 0u);
        CHECK(fs.spill.reset.count == 0u);
        CHECK(fs.spill.reset.instance_count == 1u);
        CHECK(fs.spill.reset.capacity == 5000u);
        CHECK(fs.spill.reset.overflow == 0u);
        CHECK(fs.spill.direct_max_vertices == 6);
        CHECK(fs.spill.spill_max_vertices == PENUMBRA_CONSERVATIVE_MAX_VERTICES);
        CHECK(fs.spill.direct_defines.back().name == "PENUMBRA_CONSERVATIVE_DIRECT");
        CHECK(fs.spill.spill_defines.back().name == "PENUMBRA_CONSERVATIVE_SPILL_DRAW");
        f.spill_capacity = 100;
        CHECK(penumbra::conservativeRasterSetup(f).spill.capacity == 100u);
        f.variant = ConservativeVariant::Exact;
        CHECK_FALSE(penumbra::conservativeRasterSetup(f).spill.enabled);
    }

    o.variant = ConservativeVariant::Exact;
    o.drop_degenerate = true;
    o.subpixel_bits = 8;
    const ConservativeRasterSetup s = penumbra::conservativeRasterSetup(o);
    CHECK(s.guard_band == 64.0f);
    CHECK(s.margin == doctest::Approx(1.0 / 256 + 128.0 / 1048576).epsilon(1e-6));
    CHECK(s.params.expansion.x == 0.5f + s.margin);
    CHECK(s.params.viewport == glm::vec4(0, 0, 64, 48));
    CHECK(s.params.clipping.y == doctest::Approx(3.0));
    CHECK(s.params.clipping.z == doctest::Approx(1.0 + 128.0 / 48.0));
    CHECK(s.max_vertices == PENUMBRA_CONSERVATIVE_MAX_VERTICES);
    std::string defines;
    for (const auto& d : s.defines) defines += d.name + "=" + d.value + " ";
    CHECK(defines == "PENUMBRA_CONSERVATIVE_EXACT=1 PENUMBRA_CONSERVATIVE_DROP_DEGENERATE=1 PENUMBRA_CONSERVATIVE_CLIP_TO_BOX=0 ");
    CHECK(s.params.depth == glm::vec4(-1, 1, 0, 0));

    // Emitted depth stays inside the range GL clips to (GL_ZERO_TO_ONE: [0, 1]), so no hull vertex is
    // clipped in z even for a steep plane or a triangle partly beyond the far plane.
    ConservativeRasterOptions zo = o;
    zo.depth_clip_range = glm::vec2(0.0f, 1.0f);
    zo.near_plane = glm::vec4(0, 0, 1, 0);
    const ConservativeRasterSetup zero_to_one = penumbra::conservativeRasterSetup(zo);
    const glm::vec4 steep[3] = {glm::vec4(-0.5f, -0.5f, 0.01f, 1), glm::vec4(0.5f, -0.5f, 0.99f, 1), glm::vec4(0, 0.5f, 3.0f, 1)};
    for (const auto* setup_ptr : {&s, &zero_to_one}) {
        const auto hull = penumbra::conservativeHull(steep, *setup_ptr);
        REQUIRE(hull.count > 0);
        for (int i = 0; i < hull.count; ++i) {
            CHECK(hull.positions[static_cast<size_t>(i)].z >= setup_ptr->options.depth_clip_range.x);
            CHECK(hull.positions[static_cast<size_t>(i)].z <= setup_ptr->options.depth_clip_range.y);
        }
    }
}

// ---- CPU: the exact predicate -------------------------------------------------------------------

TEST_CASE("cpu: the exact predicate counts pixels touched only on their boundary") {
    using glm::dvec2;
    auto touched = [](std::vector<dvec2> poly, int w, int h) {
        std::vector<glm::ivec2> out;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                if (penumbra::polygonTouchesPixel(poly.data(), poly.size(), x, y)) out.emplace_back(x, y);
        return out;
    };
    using V = std::vector<glm::ivec2>;
    // A point on a pixel corner touches the four pixels around it; inside a pixel, only that one.
    CHECK(touched({dvec2(3, 2)}, 8, 8) == V{{2, 1}, {3, 1}, {2, 2}, {3, 2}});
    CHECK(touched({dvec2(3.5, 2.25)}, 8, 8) == V{{3, 2}});
    // A point on a vertical pixel edge: the two pixels sharing it.
    CHECK(touched({dvec2(3, 2.5)}, 8, 8) == V{{2, 2}, {3, 2}});
    // A horizontal segment on the line y = 2 from x = 1.5 to 3: rows 1 and 2, columns 1..3.
    CHECK(touched({dvec2(1.5, 2), dvec2(3, 2)}, 8, 8) == V{{1, 1}, {2, 1}, {3, 1}, {1, 2}, {2, 2}, {3, 2}});
    // A diagonal segment through pixel corners touches the pixels it crosses and the corner-only ones.
    CHECK(touched({dvec2(1, 1), dvec2(3, 3)}, 5, 5) ==
          V{{0, 0}, {1, 0}, {0, 1}, {1, 1}, {2, 1}, {1, 2}, {2, 2}, {3, 2}, {2, 3}, {3, 3}});
    // A triangle whose hypotenuse passes exactly through pixel corners, either winding.
    const V tri = touched({dvec2(1, 1), dvec2(3, 1), dvec2(1, 3)}, 5, 5);
    CHECK(tri == touched({dvec2(1, 1), dvec2(1, 3), dvec2(3, 1)}, 5, 5));
    CHECK(tri == V{{0, 0}, {1, 0}, {2, 0}, {3, 0}, {0, 1}, {1, 1}, {2, 1}, {3, 1}, {0, 2}, {1, 2}, {2, 2}, {0, 3}, {1, 3}});
    // A gap of one double ulp separates.
    CHECK_FALSE(penumbra::polygonTouchesPixel(std::vector<dvec2>{dvec2(std::nextafter(3.0, 4.0), 0.5)}.data(), 1, 2, 0));
    CHECK(penumbra::triangleTouchesPixel(dvec2(3, -5), dvec2(3, 5), dvec2(9, 0), 2, 0));
    CHECK_FALSE(penumbra::triangleTouchesPixel(dvec2(std::nextafter(3.0, 4.0), -5), dvec2(std::nextafter(3.0, 4.0), 5),
                                               dvec2(9, 0), 2, 0));
}

TEST_CASE("cpu: the exact predicate agrees with clipping the triangle by the pixel square") {
    const uint32_t seed = testSeed();
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-2.0, 6.0);
    // Independent check: Sutherland-Hodgman of the triangle against the square, in double, away
    // from ties (a distance-to-boundary guard skips the ~1e-9-close cases the clip cannot decide).
    size_t compared = 0, touching = 0;
    for (int iteration = 0; iteration < 200000; ++iteration) {
        std::vector<glm::dvec2> tri = {{u(rng), u(rng)}, {u(rng), u(rng)}, {u(rng), u(rng)}};
        if (iteration % 4 == 0) tri[2] = tri[0] + (tri[1] - tri[0]) * std::uniform_real_distribution<double>(0, 1)(rng);
        const int x = static_cast<int>(rng() % 4), y = static_cast<int>(rng() % 4);
        std::vector<glm::dvec2> poly = tri, next;
        const double limits[4] = {static_cast<double>(x), static_cast<double>(x + 1), static_cast<double>(y),
                                  static_cast<double>(y + 1)};
        double closest = 1e300;
        for (int k = 0; k < 4; ++k) {
            next.clear();
            auto dist = [&](const glm::dvec2& p) {
                return k == 0 ? p.x - limits[0] : k == 1 ? limits[1] - p.x : k == 2 ? p.y - limits[2] : limits[3] - p.y;
            };
            for (size_t i = 0; i < poly.size(); ++i) {
                const glm::dvec2 a = poly[(i + poly.size() - 1) % poly.size()], b = poly[i];
                const double da = dist(a), db = dist(b);
                closest = std::min({closest, std::abs(da), std::abs(db)});
                if ((da >= 0) != (db >= 0)) next.push_back(a + (da / (da - db)) * (b - a));
                if (db >= 0) next.push_back(b);
            }
            poly.swap(next);
        }
        if (closest < 1e-9) continue;
        // Degenerate inputs give a clip of a segment; a non-empty clip means intersection.
        const bool clipped = !poly.empty();
        const bool sat = penumbra::polygonTouchesPixel(tri.data(), 3, x, y);
        ++compared;
        touching += sat;
        if (sat != clipped) {
            CAPTURE(iteration);
            CHECK(sat == clipped);
        }
    }
    MESSAGE("compared ", compared, " triangle/pixel pairs, ", touching, " touching");
    CHECK(compared > 150000);
}

// ---- CPU: the twin ------------------------------------------------------------------------------

TEST_CASE("cpu: the twin's hull covers every required pixel; fixed6 contains exact; over-coverage is bounded") {
    const uint32_t seed = testSeed();
    for (glm::ivec4 viewport : {glm::ivec4(0, 0, 32, 32), glm::ivec4(7, -3, 20, 29), glm::ivec4(0, 0, 1, 1)}) {
        CAPTURE(viewport.z);
        CAPTURE(viewport.w);
        // 16 subpixel bits: a margin of only 2^-16 + 2^-20 (W + G) px, so the twin's geometry itself
        // (thin thickness, case-iii extension, clipping) has to be right, not the snap slack.
        const auto fixed = makeSetup(viewport.x, viewport.y, viewport.z, viewport.w, ConservativeVariant::Fixed6, 16);
        const auto exact = makeSetup(viewport.x, viewport.y, viewport.z, viewport.w, ConservativeVariant::Exact, 16);
        TriangleGenerator gen(seed, viewport.z, viewport.w);
        uint64_t kinds[6] = {}, exact_extra = 0, fixed_extra = 0, required_total = 0, not_contained = 0;
        for (int i = 0; i < 30000; ++i) {
            const TestTriangle t = gen.next();
            CAPTURE(describeClip(t.v));
            const auto required = penumbra::conservativeRequiredPixels(t.v[0], t.v[1], t.v[2], fixed);
            required_total += required.size();
            const auto hull_fixed = penumbra::conservativeHull(t.v, fixed);
            const auto hull_exact = penumbra::conservativeHull(t.v, exact);
            kinds[static_cast<int>(hull_exact.kind)]++;
            REQUIRE(hull_fixed.kind != ConservativeHullKind::Fallback);
            REQUIRE(hull_exact.kind != ConservativeHullKind::Fallback);
            if (t.category == kNonFinite) {
                CHECK(hull_fixed.kind == ConservativeHullKind::Dropped);
                CHECK(hull_fixed.count == 0);
            }
            if (hull_fixed.kind == ConservativeHullKind::Triangle) CHECK(hull_fixed.count == 6);
            // The two-pass plan: what the direct pass emits fits its 6; the rest is spilled.
            const bool needs_spill = penumbra::conservativeNeedsSpill(t.v[0], t.v[1], t.v[2], fixed);
            CHECK(hull_fixed.spilled == needs_spill);
            if (!needs_spill) CHECK(hull_fixed.count <= kConservativeFixed6MaxVertices);
            if (needs_spill) CHECK(hull_fixed.kind != ConservativeHullKind::Triangle);
            if (hull_exact.kind == ConservativeHullKind::Triangle) CHECK(hull_exact.count <= 7);
            if (hull_exact.kind == ConservativeHullKind::Thin) CHECK(hull_exact.count <= 6);
            CHECK(hull_exact.count <= PENUMBRA_CONSERVATIVE_MAX_VERTICES);
            const auto raster_fixed = penumbra::rasterizeConservativeHull(hull_fixed, fixed);
            const auto raster_exact = penumbra::rasterizeConservativeHull(hull_exact, exact);
            auto has = [](const std::vector<glm::ivec2>& v, glm::ivec2 p) { return std::find(v.begin(), v.end(), p) != v.end(); };
            for (const auto& p : required) {
                if (!has(raster_fixed.fragments, p) || !has(raster_exact.fragments, p)) {
                    CAPTURE(p.x);
                    CAPTURE(p.y);
                    CHECK(has(raster_fixed.fragments, p));
                    CHECK(has(raster_exact.fragments, p));
                }
            }
            for (const auto& p : raster_exact.fragments) not_contained += !has(raster_fixed.fragments, p);
            // Over-coverage bound: the exact hull's pixels touch T once grown by the margin; the
            // fixed hull's by margin + one pixel (the case-iii extension); thin ones by their thickness.
            const auto poly = penumbra::conservativeReferencePolygon(t.v[0], t.v[1], t.v[2], fixed);
            auto within = [&](glm::ivec2 p, double grow) {
                // Does the square [p - grow, p + 1 + grow] touch the polygon? Scale so it is a unit square.
                std::vector<glm::dvec2> scaled;
                const double s = 1.0 / (1.0 + 2.0 * grow);
                for (const auto& q : poly) scaled.push_back((q - glm::dvec2(p) + grow) * s);
                return penumbra::polygonTouchesPixel(scaled.data(), scaled.size(), 0, 0);
            };
            const double thin_grow = hull_exact.kind == ConservativeHullKind::Thin ? 0.01 : 0.0;
            for (const auto& p : raster_exact.fragments) CHECK(within(p, exact.margin + thin_grow + 1e-4));
            for (const auto& p : raster_fixed.fragments) CHECK(within(p, fixed.margin + 2 * fixed.half_size + thin_grow + 1e-4));
            exact_extra += raster_exact.fragments.size() - std::min(raster_exact.fragments.size(), required.size());
            fixed_extra += raster_fixed.fragments.size() - std::min(raster_fixed.fragments.size(), required.size());
        }
        CHECK(not_contained == 0);
        MESSAGE("twin ", viewport.z, "x", viewport.w, ": required ", required_total, ", extra exact ", exact_extra,
                ", extra fixed6 ", fixed_extra, "; kinds dropped/culled/triangle/clipped/thin = ", kinds[0], "/", kinds[1],
                "/", kinds[2], "/", kinds[3], "/", kinds[4]);
        CHECK(kinds[static_cast<int>(ConservativeHullKind::Clipped)] > 0);
        CHECK(kinds[static_cast<int>(ConservativeHullKind::Thin)] > 0);
    }
}

namespace {

/// The compute light passes' coverage (penumbraConservativeEmit with PENUMBRA_CONSERVATIVE_BOX_ONLY,
/// then penumbraConservativeBoxPixels, the box test per pixel centre and, for unclipped triangles
/// that are not thin, penumbraConservativeRectMeetsDilatedTriangle on the pixel's 8 x 8 tile and
/// penumbraConservativeInsideDilatedTriangle on the pixel), through the CPU twins:
/// every pixel the exact predicate requires is visited. Returns the pixels visited.
uint64_t checkBoxPixels(const ConservativeRasterSetup& setup, const TestTriangle& t, uint64_t& missed) {
    const glm::ivec4 viewport(setup.options.viewport_x, setup.options.viewport_y, setup.width(), setup.height());
    const auto hull = penumbra::conservativeHull(t.v, setup);
    const auto required = penumbra::conservativeRequiredPixels(t.v[0], t.v[1], t.v[2], setup);
    if (hull.count == 0) {
        missed += required.size();  // a dropped triangle touches no pixel
        return 0;
    }
    const glm::ivec4 range = penumbra::conservativeBoxPixels(hull.box, viewport);
    const bool triangle = hull.kind == ConservativeHullKind::Triangle;
    auto visited = [&](glm::ivec2 p) {  // window pixel
        const glm::vec2 centre = glm::vec2(p) + 0.5f;
        const glm::vec2 relative = glm::vec2(p - glm::ivec2(viewport)) + 0.5f;
        // Its 8 x 8 tile of the range (the hard compute pass's), culled as a whole first.
        const glm::ivec2 tile = glm::ivec2(range) + ((p - glm::ivec2(range)) / 8) * 8 - glm::ivec2(viewport);
        const glm::vec2 tile_lo = glm::vec2(tile) + 0.5f, tile_hi = tile_lo + 7.0f;
        return p.x >= range.x && p.y >= range.y && p.x <= range.z && p.y <= range.w && centre.x >= hull.box.x &&
               centre.y >= hull.box.y && centre.x <= hull.box.z && centre.y <= hull.box.w &&
               (!triangle || (penumbra::conservativeRectMeetsDilatedTriangle(tile_lo, tile_hi, hull.triangle, hull.dilation) &&
                              penumbra::conservativeInsideDilatedTriangle(relative, hull.triangle, hull.dilation)));
    };
    for (const auto& p : required) {
        if (!visited(p + glm::ivec2(viewport))) {
            ++missed;
            CAPTURE(describeClip(t.v));
            CAPTURE(p.x);
            CAPTURE(p.y);
            CHECK(visited(p + glm::ivec2(viewport)));
        }
    }
    uint64_t count = 0;
    for (int y = range.y; y <= range.w; ++y)
        for (int x = range.x; x <= range.z; ++x) count += visited(glm::ivec2(x, y));
    return count;
}

void boxPixelsSweep(uint32_t seed, int count) {
    for (glm::ivec4 viewport : {glm::ivec4(0, 0, 32, 32), glm::ivec4(7, -3, 20, 29), glm::ivec4(0, 0, 1, 1)}) {
        for (const auto variant : {ConservativeVariant::Fixed6, ConservativeVariant::Exact}) {
            const auto setup = makeSetup(viewport.x, viewport.y, viewport.z, viewport.w, variant, 16);
            TriangleGenerator gen(seed, viewport.z, viewport.w);
            uint64_t missed = 0, visited = 0, required = 0;
            for (int i = 0; i < count; ++i) {
                const TestTriangle t = gen.next();
                visited += checkBoxPixels(setup, t, missed);
                required += penumbra::conservativeRequiredPixels(t.v[0], t.v[1], t.v[2], setup).size();
            }
            MESSAGE("box pixels, ", viewport.z, "x", viewport.w, " variant ", int(variant), ": ", count, " triangles, ", required,
                    " required pixels, ", visited, " visited, ", missed, " missed");
            CHECK(missed == 0);
        }
    }
}

}  // namespace

TEST_CASE("cpu: the box's pixel range (the compute light passes' coverage) holds every required pixel, 10^5 triangles") {
    boxPixelsSweep(testSeed(), int(defaultCount(100000) / 6 + 1));
}

TEST_CASE("cpu: NaN/Inf drop, degenerate triangles cover what they touch, drop_degenerate drops them") {
    const auto setup = makeSetup(0, 0, 16, 16, ConservativeVariant::Fixed6, 8);
    const auto drop = makeSetup(0, 0, 16, 16, ConservativeVariant::Exact, 8, true);
    auto px = [](float x, float y) { return glm::vec4(x / 8.0f - 1.0f, y / 8.0f - 1.0f, 0.0f, 1.0f); };
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    for (float bad : {nan, inf, -inf}) {
        for (int k = 0; k < 12; ++k) {
            glm::vec4 v[3] = {px(2, 2), px(9, 3), px(4, 8)};
            v[k / 4][k % 4] = bad;
            CHECK(penumbra::conservativeHull(v, setup).kind == ConservativeHullKind::Dropped);
            CHECK(penumbra::conservativeHull(v, setup).count == 0);
            CHECK(penumbra::conservativeRequiredPixels(v[0], v[1], v[2], setup).empty());
        }
    }
    using V = std::vector<glm::ivec2>;
    auto covered = [&](glm::vec4 a, glm::vec4 b, glm::vec4 c, const ConservativeRasterSetup& s) {
        V out = penumbra::rasterizeConservativeHull(penumbra::conservativeHull(a, b, c, s), s).fragments;
        std::sort(out.begin(), out.end(), [](glm::ivec2 l, glm::ivec2 r) { return l.y != r.y ? l.y < r.y : l.x < r.x; });
        return out;
    };
    // Three coincident points on a pixel corner: exactly the four pixels around it.
    CHECK(covered(px(5, 6), px(5, 6), px(5, 6), setup) == V{{4, 5}, {5, 5}, {4, 6}, {5, 6}});
    CHECK(penumbra::conservativeHull(px(5, 6), px(5, 6), px(5, 6), setup).kind == ConservativeHullKind::Thin);
    // A collinear triangle on the pixel line y = 4 from x = 2 to 5: rows 3 and 4, columns 1..5.
    CHECK(covered(px(2, 4), px(5, 4), px(3.5f, 4), setup) ==
          V{{1, 3}, {2, 3}, {3, 3}, {4, 3}, {5, 3}, {1, 4}, {2, 4}, {3, 4}, {4, 4}, {5, 4}});
    // drop_degenerate drops them (and keeps proper triangles).
    CHECK(penumbra::conservativeHull(px(5, 6), px(5, 6), px(5, 6), drop).kind == ConservativeHullKind::Dropped);
    CHECK(penumbra::conservativeHull(px(2, 4), px(5, 4), px(3.5f, 4), drop).kind == ConservativeHullKind::Dropped);
    CHECK(penumbra::conservativeHull(px(2, 4), px(5, 4), px(3.5f, 5), drop).kind == ConservativeHullKind::Triangle);
    // Both windings give the same coverage.
    CHECK(covered(px(2, 3), px(9, 4), px(4, 11), setup) == covered(px(2, 3), px(4, 11), px(9, 4), setup));
    // A triangle with a vertex on a pixel corner covers the pixel diagonally across that corner.
    const V corner = covered(px(4, 4), px(8, 4), px(4, 8), setup);
    CHECK(std::find(corner.begin(), corner.end(), glm::ivec2(3, 3)) != corner.end());
    CHECK(std::find(corner.begin(), corner.end(), glm::ivec2(2, 2)) == corner.end());
}

TEST_CASE("cpu: near-plane crossing and 1e5..1e9-pixel vertices are clipped first, then dilated") {
    const auto setup = makeSetup(0, 0, 32, 32, ConservativeVariant::Fixed6, 8);
    // One vertex behind the near plane (z < -w): the kept part is a quadrilateral.
    const glm::vec4 a(-0.5f, -0.5f, 0.5f, 1.0f), b(0.6f, -0.4f, 0.2f, 1.0f), c(0.1f, 0.3f, -3.0f, 1.0f);
    const auto poly = penumbra::conservativeReferencePolygon(a, b, c, setup);
    CHECK(poly.size() == 4);
    const auto hull = penumbra::conservativeHull(a, b, c, setup);
    CHECK(hull.kind == ConservativeHullKind::Clipped);
    CHECK(hull.count == 8);  // the exact dilation of a quadrilateral: n + 4
    // Entirely behind the near plane, or behind the eye: nothing.
    CHECK(penumbra::conservativeHull(glm::vec4(0, 0, -2, 1), glm::vec4(0.5f, 0, -2, 1), glm::vec4(0, 0.5f, -2, 1), setup).kind ==
          ConservativeHullKind::Culled);
    CHECK(penumbra::conservativeHull(glm::vec4(0, 0, 0, -1), glm::vec4(0.5f, 0, 0, -1), glm::vec4(0, 0.5f, 0, -1), setup).count == 0);
    // Huge pixel coordinates with an edge through the viewport: the twin still covers every pixel.
    std::mt19937 rng(testSeed());
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int i = 0; i < 2000; ++i) {
        const double angle = u(rng) * 6.283185307179586, reach = std::pow(10.0, 5.0 + 4.0 * u(rng));
        const glm::dvec2 q(u(rng) * 32.0, u(rng) * 32.0), d(std::cos(angle), std::sin(angle));
        auto clip = [&](glm::dvec2 p) { return glm::vec4(static_cast<float>(p.x / 16.0 - 1.0), static_cast<float>(p.y / 16.0 - 1.0), 0.0f, 1.0f); };
        const glm::vec4 v0 = clip(q + reach * d), v1 = clip(q - reach * d), v2 = clip(q + reach * glm::dvec2(-d.y, d.x) * u(rng));
        const auto required = penumbra::conservativeRequiredPixels(v0, v1, v2, setup);
        const auto raster = penumbra::rasterizeConservativeHull(penumbra::conservativeHull(v0, v1, v2, setup), setup);
        for (const auto& p : required) {
            if (std::find(raster.fragments.begin(), raster.fragments.end(), p) == raster.fragments.end()) {
                CAPTURE(i);
                FAIL_CHECK("missed pixel (" << p.x << ", " << p.y << ")");
            }
        }
    }
}

// ---- GL: the emitter on the driver --------------------------------------------------------------

TEST_CASE("gl: >= 10^5 random triangles per variant, 0 missed pixels vs the exact predicate") {
    context();
    const uint32_t seed = testSeed();
    const size_t count = defaultCount(100000);
    MESSAGE(count, " triangles per variant on ", context().renderer(), " (", context().platform(), "), GL_SUBPIXEL_BITS ",
            subpixelBits());
    // Fixed6 through its two-pass plan (direct pass at 6 + spill pass, together) and through the
    // single-pass emitter (13; what a geometry stage without a spill hook, e.g. the hard-shadow
    // light pass, gets); Exact always single pass.
    const std::pair<ConservativeVariant, Passes> runs[] = {{ConservativeVariant::Fixed6, Passes::Plan},
                                                           {ConservativeVariant::Fixed6, Passes::Single},
                                                           {ConservativeVariant::Exact, Passes::Plan}};
    for (const auto& [variant, passes] : runs) {
        const std::string label = std::string(penumbra::conservativeVariantName(variant)) +
                                  (variant == ConservativeVariant::Exact ? "" : passes == Passes::Plan ? " two-pass" : " single pass");
        const auto start = std::chrono::steady_clock::now();
        // Most triangles in a 32 x 32 viewport at (3, 5); a tenth in a 20 x 29 one at (0, 0).
        CoverageStats stats =
            runRandom(variant, seed, count - count / 10, glm::ivec4(3, 5, 32, 32), glm::ivec2(40, 40), false, passes);
        stats.merge(runRandom(variant, seed ^ 0x9e3779b9u, count / 10, glm::ivec4(0, 0, 20, 29), glm::ivec2(20, 29), false, passes));
        MESSAGE(stats.summary(label, seed), "\n  (", seconds(start), " s)");
        requireClean(stats);
        CHECK(stats.triangles == count);
        if (variant == ConservativeVariant::Fixed6 && passes == Passes::Plan) {
            CHECK(stats.two_pass);
            CHECK(stats.spill_gpu > count / 10);  // the generator's near-plane, huge and random-clip ones
        }
    }
}

TEST_CASE("gl: the Fixed-6 direct program declares max_vertices <= 6; the spill and single passes 13") {
    context();
    const auto fixed = makeSetup(0, 0, 32, 32, ConservativeVariant::Fixed6, subpixelBits());
    const auto exact = makeSetup(0, 0, 32, 32, ConservativeVariant::Exact, subpixelBits());
    CHECK(fixed.spill.enabled);
    CHECK_FALSE(exact.spill.enabled);
    CHECK(fixed.spill.direct_max_vertices == 6);
    CHECK(fixed.spill.spill_max_vertices == PENUMBRA_CONSERVATIVE_MAX_VERTICES);
    // The declared value as the assembled text states it: find the layout, resolve macros.
    auto declared = [](const penumbra::ShaderDefines& defines) {
        const std::string text = penumbra::assembleShader(kGeom, defines).text;
        std::map<std::string, std::string> macros;
        std::istringstream in(text);
        std::string line, value;
        int found = -1, layouts = 0;
        bool skipping = false;  // inside an inactive #if branch of the entry (DIRECT selects one layout)
        std::vector<bool> stack;
        auto eval = [&](std::string cond) {
            // Only what the entry's layout conditions use: NAME, !NAME, NAME && NAME.
            bool result = true;
            std::istringstream c(cond);
            std::string tok;
            while (c >> tok) {
                if (tok == "&&") continue;
                const bool negate = tok[0] == '!';
                if (negate) tok = tok.substr(1);
                const bool v = macros.count(tok) && macros[tok] != "0";
                result = result && (negate ? !v : v);
            }
            return result;
        };
        while (std::getline(in, line)) {
            std::istringstream l(line);
            std::string first;
            l >> first;
            if (first == "#if") {
                std::string rest;
                std::getline(l, rest);
                stack.push_back(skipping);
                skipping = skipping || !eval(rest);
            } else if (first == "#ifndef" || first == "#ifdef") {
                std::string name;
                l >> name;
                stack.push_back(skipping);
                skipping = skipping || (first == "#ifndef" ? macros.count(name) != 0 : macros.count(name) == 0);
            } else if (first == "#else") {
                const bool outer = stack.empty() ? false : stack.back();
                skipping = outer || !skipping;
            } else if (first == "#endif") {
                skipping = stack.empty() ? false : stack.back();
                if (!stack.empty()) stack.pop_back();
            } else if (skipping) {
                continue;
            } else if (first == "#define") {
                std::string name;
                l >> name >> value;
                macros[name] = value;
            } else if (first.rfind("layout(", 0) == 0 && line.find("max_vertices") != std::string::npos) {
                ++layouts;
                std::string v = line.substr(line.find('=', line.find("max_vertices")) + 1);
                v = v.substr(0, v.find(')'));
                v.erase(std::remove(v.begin(), v.end(), ' '), v.end());
                for (int depth = 0; depth < 8 && macros.count(v); ++depth) v = macros[v];
                found = std::atoi(v.c_str());
            }
        }
        CHECK(layouts == 1);
        return found;
    };
    const int direct = declared(fixed.spill.direct_defines);
    MESSAGE("assembled Fixed-6 direct geometry shader declares max_vertices = ", direct);
    CHECK(direct >= 4);
    CHECK(direct <= 6);
    CHECK(declared(fixed.spill.spill_defines) == PENUMBRA_CONSERVATIVE_MAX_VERTICES);
    CHECK(declared(fixed.defines) == PENUMBRA_CONSERVATIVE_MAX_VERTICES);
    CHECK(declared(exact.defines) == PENUMBRA_CONSERVATIVE_MAX_VERTICES);
    // And what the driver linked.
    auto linked = [](const penumbra::ShaderDefines& defines) {
        penumbra::gl::Program& p = program(defines, false, false);
        GLint vertices = 0;
        glGetProgramiv(p.id(), GL_GEOMETRY_VERTICES_OUT, &vertices);
        return vertices;
    };
    CHECK(linked(fixed.spill.direct_defines) == 6);
    CHECK(linked(fixed.spill.spill_defines) == PENUMBRA_CONSERVATIVE_MAX_VERTICES);
    CHECK(linked(fixed.defines) == PENUMBRA_CONSERVATIVE_MAX_VERTICES);
    // The direct snippet refuses the exact variant and a missing spill hook.
    penumbra::ShaderLibrary lib = penumbra::ShaderLibrary::embedded();
    lib.add("t/no_spill_hook.geom.glsl",
            "#version 450\nlayout(triangles) in;\nlayout(triangle_strip, max_vertices = 6) out;\n"
            "#define PENUMBRA_CONSERVATIVE_EMIT_VERTEX(p, b) EmitVertex()\n"
            "#include \"penumbra/conservative_raster/conservative_raster.glsl\"\nvoid main() {}\n");
    const std::string e = errorOf(
        [&] { penumbra::gl::compileShader(GL_GEOMETRY_SHADER, "t/no_spill_hook.geom.glsl", {{"PENUMBRA_CONSERVATIVE_DIRECT", "1"}}, lib); });
    INFO(e);
    CHECK(contains(e, "PENUMBRA_CONSERVATIVE_SPILL"));
    const std::string x = errorOf([&] {
        penumbra::gl::compileShader(GL_GEOMETRY_SHADER, kGeom, {{"PENUMBRA_CONSERVATIVE_DIRECT", "1"}, {"PENUMBRA_CONSERVATIVE_EXACT", "1"}});
    });
    INFO(x);
    CHECK(contains(x, "PENUMBRA_CONSERVATIVE_DIRECT=1 is the Fixed-6 pass"));
}

TEST_CASE("gl: a full spill buffer counts its overflow and keeps the indirect count at 3 * capacity") {
    context();
    const uint32_t seed = testSeed();
    const auto setup = makeSetup(3, 5, 32, 32, ConservativeVariant::Fixed6, subpixelBits());
    TriangleGenerator generator(seed, 32, 32);
    std::vector<TestTriangle> triangles(20000);
    std::vector<glm::vec4> vertices;
    for (auto& t : triangles) {
        t = generator.make(kNearPlane);
        vertices.insert(vertices.end(), t.v, t.v + 3);
    }
    const std::vector<glm::ivec2> tiles(triangles.size(), glm::ivec2(3, 5));
    uint64_t predicted = 0;
    for (const auto& t : triangles) predicted += penumbra::conservativeNeedsSpill(t.v[0], t.v[1], t.v[2], setup);
    REQUIRE(predicted > 1000);
    const uint32_t capacity = 1000;
    const Recorded rec = record(setup, glm::ivec2(40), vertices, tiles, nullptr, Passes::Plan, capacity);
    MESSAGE("capacity ", capacity, ": ", predicted, " predicted spills, header count ", rec.spill.count, ", overflow ",
            rec.spill.overflow);
    CHECK(rec.spill.count == 3u * capacity);
    CHECK(rec.spill.instance_count == 1u);
    CHECK(rec.spill.first == 0u);
    CHECK(rec.spill.capacity == capacity);
    CHECK(rec.spill.overflow == predicted - capacity);
    // Which spilled triangles found room is up to the GPU's ordering; the direct pass's own
    // triangles are unaffected by the overflow: they miss nothing.
    CoverageStats direct;
    for (size_t i = 0; i < triangles.size(); ++i) {
        const glm::vec4 clip[3] = {rec.clips[3 * i], rec.clips[3 * i + 1], rec.clips[3 * i + 2]};
        if (penumbra::conservativeNeedsSpill(clip[0], clip[1], clip[2], setup)) continue;
        checkTriangle(setup, clip, &rec.words[i * kWords], tiles[i], triangles[i].category, direct);
    }
    requireClean(direct);
}

TEST_CASE("gl: the spill helpers validate at load time and return a Status per frame") {
    context();
    const auto fixed = makeSetup(0, 0, 32, 32, ConservativeVariant::Fixed6, subpixelBits(), false, false, 100);
    const auto exact = makeSetup(0, 0, 32, 32, ConservativeVariant::Exact, subpixelBits());
    penumbra::gl::Buffer buffer(static_cast<size_t>(fixed.spill.buffer_bytes));
    const penumbra::BufferRange whole{buffer.id(), 0, fixed.spill.buffer_bytes};
    CHECK_NOTHROW(penumbra::gl::validateConservativeSpill(fixed, whole));
    CHECK(contains(errorOf([&] { penumbra::gl::validateConservativeSpill(exact, whole); }), "no spill plan"));
    CHECK(contains(errorOf([&] { penumbra::gl::validateConservativeSpill(fixed, whole.sub(0, 64)); }), "needs"));
    CHECK(contains(errorOf([&] { penumbra::gl::validateConservativeSpill(fixed, {buffer.id(), 4, fixed.spill.buffer_bytes}); }),
                   "not a multiple"));
#ifdef NDEBUG  // misuse asserts in debug builds; in release it returns a Status and issues no GL call
    CHECK(penumbra::gl::beginConservativeSpill(exact, whole) == penumbra::Status::InvalidArgument);
    CHECK(penumbra::gl::beginConservativeSpill(fixed, whole.sub(0, 64)) == penumbra::Status::RangeTooSmall);
    CHECK(penumbra::gl::drawConservativeSpill(fixed, {buffer.id(), 2, fixed.spill.buffer_bytes}) == penumbra::Status::Misaligned);
#endif
    penumbra::gl::checkErrors("spill helpers");
}

TEST_CASE("gl: NaN/Inf and degenerate triangles; drop_degenerate permutation") {
    context();
    const uint32_t seed = testSeed();
    std::mt19937 rng(seed);
    for (ConservativeVariant variant : {ConservativeVariant::Fixed6, ConservativeVariant::Exact}) {
        for (bool drop : {false, true}) {
            CAPTURE(drop);
            const auto setup = makeSetup(0, 0, 32, 32, variant, subpixelBits(), drop);
            TriangleGenerator gen(seed, 32, 32);
            std::vector<TestTriangle> triangles;
            std::vector<glm::vec4> vertices;
            for (int i = 0; i < 6000; ++i) {
                // Exactly degenerate ones (coincident grid points, grid-aligned segments), NaN/Inf, and normal ones.
                TestTriangle t = gen.make(i % 3 == 0 ? kGrid : i % 3 == 1 ? kNonFinite : kSmall);
                if (i % 3 == 0) {
                    if (i % 2) t.v[1] = t.v[0], t.v[2] = t.v[0];
                    else t.v[1].x = t.v[0].x, t.v[2].x = t.v[0].x;  // three points on a vertical line
                }
                triangles.push_back(t);
                vertices.insert(vertices.end(), t.v, t.v + 3);
            }
            const std::vector<glm::ivec2> tiles(triangles.size(), glm::ivec2(0));
            const Recorded rec = record(setup, glm::ivec2(32), vertices, tiles);
            uint64_t degenerate_fragments = 0, nonfinite_fragments = 0, degenerate_total = 0;
            CoverageStats stats;
            for (size_t i = 0; i < triangles.size(); ++i) {
                const uint32_t fragments = rec.words[i * kWords + PENUMBRA_CONSERVATIVE_RECORD_FRAGMENTS];
                if (i % 3 == 1) nonfinite_fragments += fragments;
                const glm::vec4 clip[3] = {rec.clips[3 * i], rec.clips[3 * i + 1], rec.clips[3 * i + 2]};
                if (i % 3 == 0) {
                    degenerate_total++;
                    degenerate_fragments += fragments;
                    if (drop) continue;  // contract: dropped
                }
                checkTriangle(setup, clip, &rec.words[i * kWords], glm::ivec2(0), triangles[i].category, stats);
            }
            if (rec.two_pass) {  // over all triangles, the dropped ones included
                uint64_t predicted = 0;
                for (size_t i = 0; i < triangles.size(); ++i) {
                    predicted += penumbra::conservativeNeedsSpill(rec.clips[3 * i], rec.clips[3 * i + 1], rec.clips[3 * i + 2], setup);
                }
                CHECK(rec.spill.count / 3u + rec.spill.overflow == predicted);
                CHECK(rec.spill.overflow == 0u);
            }
            CHECK(nonfinite_fragments == 0);
            if (drop) CHECK(degenerate_fragments == 0);
            else CHECK(degenerate_fragments > 0);  // and checkTriangle proved them conservative
            requireClean(stats);
            const std::string label = std::string(penumbra::conservativeVariantName(variant)) + (drop ? " drop_degenerate" : "");
            MESSAGE(label, ": ", degenerate_total,
                    " exactly degenerate triangles produced ", degenerate_fragments, " fragments; NaN/Inf: ", nonfinite_fragments);
        }
    }
}

TEST_CASE("gl: the fragment-side box clip keeps every required pixel and only trims") {
    context();
    const uint32_t seed = testSeed();
    const size_t count = defaultCount(100000) / 5;
    for (ConservativeVariant variant : {ConservativeVariant::Fixed6, ConservativeVariant::Exact}) {
        const CoverageStats clipped = runRandom(variant, seed, count, glm::ivec4(0, 0, 32, 32), glm::ivec2(32), true);
        const CoverageStats plain = runRandom(variant, seed, count, glm::ivec4(0, 0, 32, 32), glm::ivec2(32), false);
        MESSAGE(clipped.summary(std::string(penumbra::conservativeVariantName(variant)) + " + box clip", seed));
        requireClean(clipped);
        CHECK(clipped.covered <= plain.covered);
        // The exact hull lies inside the box (up to pixel centres within the snap of its sides); the
        // fixed hull's case-iii pixels mostly do not.
        if (variant == ConservativeVariant::Exact) CHECK(static_cast<double>(clipped.covered) >= 0.9999 * static_cast<double>(plain.covered));
        if (variant == ConservativeVariant::Fixed6) CHECK(clipped.covered < plain.covered);
        MESSAGE("box clip removed ", plain.covered - clipped.covered, " of ", plain.covered, " covered pixels");
    }
}

// Small triangles anywhere in the largest viewport (float spacing 2^-10 px at 16384), each with
// its own tile.
static void largeViewport(uint32_t seed, size_t count) {
    const int size = std::min(16384, penumbra::gl::getInteger(GL_MAX_FRAMEBUFFER_WIDTH));
    for (ConservativeVariant variant : {ConservativeVariant::Fixed6, ConservativeVariant::Exact}) {
        const auto setup = makeSetup(0, 0, size, size, variant, subpixelBits(), false, false, static_cast<uint32_t>(count));
        std::mt19937 rng(seed);
        std::uniform_real_distribution<double> u(0.0, 1.0);
        std::vector<TestTriangle> triangles(count);
        std::vector<glm::vec4> vertices;
        std::vector<glm::ivec2> tiles;
        for (auto& t : triangles) {
            // Extent <= 24 px so the dilation (<= 1.5 px + the case-iii pixel) stays in the tile; many
            // near the far corner where float spacing is coarsest.
            const double extent = std::pow(10.0, -3.0 + 4.38 * u(rng));
            const glm::dvec2 base = u(rng) < 0.5 ? glm::dvec2(size - 30, size - 30) * glm::dvec2(u(rng) * 0.01 + 0.99, u(rng) * 0.01 + 0.99)
                                                  : glm::dvec2(u(rng), u(rng)) * (size - 30.0);
            glm::dvec2 lo(1e300);
            for (auto& v : t.v) {
                const glm::dvec2 p = base + 3.0 + extent * glm::dvec2(u(rng), u(rng));
                const double w = std::pow(10.0, u(rng) - 0.5);
                v = glm::vec4(static_cast<float>((p.x / size * 2 - 1) * w), static_cast<float>((p.y / size * 2 - 1) * w),
                              0.0f, static_cast<float>(w));
                lo = glm::min(lo, p);
            }
            t.category = extent < 1 ? kSubPixel : extent < 8 ? kSmall : kLarge;
            vertices.insert(vertices.end(), t.v, t.v + 3);
            tiles.push_back(glm::ivec2(glm::floor(lo)) - 3);
        }
        const Recorded rec = record(setup, glm::ivec2(size), vertices, tiles);
        CoverageStats stats = checkAll(setup, triangles, rec.clips, rec.words, tiles);
        addSpill(rec, stats);
        MESSAGE(stats.summary(std::string(penumbra::conservativeVariantName(variant)) + " in " + std::to_string(size) + "^2 (margin " +
                                  std::to_string(setup.margin) + " px)",
                              seed));
        requireClean(stats);
    }
}

// World coordinates around 1e5 through an engine-style float view-projection in the vertex stage.
static void farFromOrigin(uint32_t seed, size_t count) {
    for (ConservativeVariant variant : {ConservativeVariant::Fixed6, ConservativeVariant::Exact}) {
        const auto setup = makeSetup(0, 0, 32, 32, variant, subpixelBits(), false, false, static_cast<uint32_t>(count));
        std::mt19937 rng(seed);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        const glm::dvec3 target(1e5, -1e5, 1e5);
        const glm::dvec3 eye = target + glm::dvec3(3.0, 2.0, 6.0);
        // An engine's float view-projection applied to float world positions near 1e5.
        const glm::dmat4 view_projection = glm::perspective(1.0, 1.0, 0.1, 100.0) * glm::lookAt(eye, target, glm::dvec3(0, 1, 0));
        const glm::mat4 matrix(view_projection);
        std::vector<TestTriangle> triangles(count);
        std::vector<glm::vec4> vertices;
        for (auto& t : triangles) {
            const glm::dvec3 centre = target + 2.0 * glm::dvec3(u(rng), u(rng), u(rng));
            const double extent = std::pow(10.0, 1.35 * u(rng) - 0.65);  // 0.01 .. 5 units = 0.04 .. 20 px
            for (auto& v : t.v) v = glm::vec4(glm::vec3(centre + extent * glm::dvec3(u(rng), u(rng), u(rng))), 1.0f);
            if (rng() % 5 == 0) t.v[2] = t.v[0];  // degenerate
            t.category = extent < 0.05 ? kSubPixel : extent < 0.3 ? kSmall : kLarge;
            vertices.insert(vertices.end(), t.v, t.v + 3);
        }
        const std::vector<glm::ivec2> tiles(count, glm::ivec2(0));
        const Recorded rec = record(setup, glm::ivec2(32), vertices, tiles, &matrix);
        // The vertex stage's float product loses ~1e5 * 2^-24 world units; the contract is about the
        // triangle the emitter received, so the ground truth uses the recorded clip coordinates.
        double worst = 0;
        for (size_t i = 0; i < vertices.size(); ++i) {
            const glm::dvec4 exact = view_projection * glm::dvec4(glm::dvec3(vertices[i]), 1.0);
            if (exact.w < 1.0) continue;  // near the eye plane any error is magnified; not the point here
            worst = std::max(worst, 16.0 * std::abs(exact.x / exact.w - rec.clips[i].x / rec.clips[i].w));
        }
        CoverageStats stats = checkAll(setup, triangles, rec.clips, rec.words, tiles);
        addSpill(rec, stats);
        MESSAGE(stats.summary(std::string(penumbra::conservativeVariantName(variant)) + " at 1e5", seed),
                "\n  (the vertex stage's float product itself moved vertices with w >= 1 by up to ", worst,
                " px from their double-precision projection)");
        requireClean(stats);
    }
}

TEST_CASE("gl: a 16384 x 16384 viewport: small triangles anywhere, tiles per triangle") {
    context();
    const uint32_t seed = testSeed();
    largeViewport(seed, defaultCount(100000) / 5);
}

TEST_CASE("gl: far from the origin: world coordinates around 1e5 through a camera looking there") {
    context();
    const uint32_t seed = testSeed();
    farFromOrigin(seed, defaultCount(100000) / 5);
}

TEST_CASE("gl: emitted depth follows the triangle's plane inside it") {
    context();
    const uint32_t seed = testSeed();
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const int size = 64;
    for (ConservativeVariant variant : {ConservativeVariant::Fixed6, ConservativeVariant::Exact}) {
        const auto setup = makeSetup(0, 0, size, size, variant, subpixelBits());
        penumbra::gl::Program p = penumbra::gl::buildProgram({"penumbra/conservative_raster/conservative_raster.vert.glsl",
                                                              "penumbra/conservative_raster/conservative_raster.geom.glsl",
                                                              "penumbra/conservative_raster/conservative_raster.frag.glsl"},
                                                             setup.defines);
        penumbra::gl::Texture depth(GL_TEXTURE_2D), ids(GL_TEXTURE_2D);
        glTextureStorage2D(depth.id(), 1, GL_DEPTH_COMPONENT32F, size, size);
        glTextureStorage2D(ids.id(), 1, GL_R32UI, size, size);
        GLuint fbo = 0, vao = 0;
        glCreateFramebuffers(1, &fbo);
        glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, depth.id(), 0);
        glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, ids.id(), 0);
        REQUIRE(glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE);
        glCreateVertexArrays(1, &vao);
        penumbra::gl::Buffer params(sizeof(setup.params), &setup.params);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo);
        glViewport(0, 0, size, size);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_ALWAYS);
        glBindVertexArray(vao);
        p.use();
        glUniform1ui(8, 0u);
        glBindBufferBase(GL_UNIFORM_BUFFER, PENUMBRA_CONSERVATIVE_PARAMS_BINDING, params.id());
        double worst = 0, steepest = 0;  // steepest: the largest |dz/dx| + |dz/dy| (window depth per pixel)
        size_t checked = 0, marked = 0;
        for (int iteration = 0; iteration < 60; ++iteration) {
            glm::vec4 v[3];
            glm::dvec2 px[3];
            for (int k = 0; k < 3; ++k) {
                px[k] = glm::dvec2(4 + 56 * u(rng), 4 + 56 * u(rng));
                const double w = 0.5 + 2 * u(rng), z = u(rng) - 0.5;
                v[k] = glm::vec4(static_cast<float>((px[k].x / size * 2 - 1) * w), static_cast<float>((px[k].y / size * 2 - 1) * w),
                                 static_cast<float>(z * w), static_cast<float>(w));
            }
            const double area = (px[1].x - px[0].x) * (px[2].y - px[0].y) - (px[1].y - px[0].y) * (px[2].x - px[0].x);
            if (std::abs(area) < 200) continue;  // keep the plane gentle so no hull vertex clamps
            auto vbo = penumbra::gl::Buffer(sizeof v, v);
            glVertexArrayVertexBuffer(vao, 0, vbo.id(), 0, sizeof(glm::vec4));
            glVertexArrayAttribFormat(vao, 0, 4, GL_FLOAT, GL_FALSE, 0);
            glVertexArrayAttribBinding(vao, 0, 0);
            glEnableVertexArrayAttrib(vao, 0);
            const float one = 1.0f;
            const GLuint zero = 0;
            glClearNamedFramebufferfv(fbo, GL_DEPTH, 0, &one);
            glClearNamedFramebufferuiv(fbo, GL_COLOR, 0, &zero);
            glDrawArrays(GL_TRIANGLES, 0, 3);
            std::vector<float> depths(size * size);
            std::vector<uint32_t> marks(size * size);
            glGetTextureImage(depth.id(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, static_cast<GLsizei>(depths.size() * 4), depths.data());
            glGetTextureImage(ids.id(), 0, GL_RED_INTEGER, GL_UNSIGNED_INT, static_cast<GLsizei>(marks.size() * 4), marks.data());
            // The plane in double from the same float clip coordinates, at interior pixel centres.
            double zc[3];
            glm::dvec2 pc[3];
            for (int k = 0; k < 3; ++k) {
                pc[k] = (glm::dvec2(v[k].x, v[k].y) / static_cast<double>(v[k].w) + 1.0) * (size / 2.0);
                zc[k] = static_cast<double>(v[k].z) / v[k].w;
            }
            const double a2 = (pc[1].x - pc[0].x) * (pc[2].y - pc[0].y) - (pc[1].y - pc[0].y) * (pc[2].x - pc[0].x);
            const double gx = 0.5 * ((zc[1] - zc[0]) * (pc[2].y - pc[0].y) - (zc[2] - zc[0]) * (pc[1].y - pc[0].y)) / a2;
            const double gy = 0.5 * ((zc[2] - zc[0]) * (pc[1].x - pc[0].x) - (zc[1] - zc[0]) * (pc[2].x - pc[0].x)) / a2;
            steepest = std::max(steepest, std::abs(gx) + std::abs(gy));
            for (int y = 0; y < size; ++y) {
                for (int x = 0; x < size; ++x) {
                    marked += marks[y * size + x] == 1u;
                    const glm::dvec2 c(x + 0.5, y + 0.5);
                    double l[3];
                    for (int k = 0; k < 3; ++k) {
                        const glm::dvec2 a = pc[(k + 1) % 3], b = pc[(k + 2) % 3];
                        l[k] = ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)) / a2;
                    }
                    if (std::min({l[0], l[1], l[2]}) < 0.02) continue;
                    const double want = 0.5 * (l[0] * zc[0] + l[1] * zc[1] + l[2] * zc[2]) + 0.5;
                    worst = std::max(worst, std::abs(depths[y * size + x] - want));
                    ++checked;
                }
            }
        }
        MESSAGE(std::string(penumbra::conservativeVariantName(variant)), ": depth at ", checked, " interior pixel centres within ", worst,
                " of the triangle's plane (steepest plane ", steepest, " per pixel); ", marked, " pixels marked with id 1");
        CHECK(checked > 5000);
        // 2e-5 holds where the rasteriser interpolates in correctly rounded float (llvmpipe: < 1e-6).
        // GL leaves the precision of depth interpolation to the implementation, and hardware
        // interpolates from hull vertices snapped to its subpixel grid (up to 2^-9 px at 8 bits)
        // that lie up to 1.5 px outside the triangle, so its error scales with the plane's slope
        // (here up to ~0.1 per pixel): the H200 (driver 580.159) measured 9.2e-5 (Fixed-6) and
        // 1.08e-4 (Exact). The portable bound, 5e-4, is about 4.6x that and 1/1000 of the range of
        // window depths drawn (0.25 .. 0.75).
        PENUMBRA_CHECK_BITWISE("conservative raster: emitted depth within 2e-5 of the triangle's plane", worst < 2e-5);
        CHECK(worst < 5e-4);
        CHECK(marked > checked);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glDisable(GL_DEPTH_TEST);
        glDeleteFramebuffers(1, &fbo);
        glDeleteVertexArrays(1, &vao);
        penumbra::gl::checkErrors("depth test");
    }
}

TEST_CASE("gl: a snippet without its hook is a compile error naming the hook") {
    context();
    penumbra::ShaderLibrary lib = penumbra::ShaderLibrary::embedded();
    lib.add("t/no_hook.geom.glsl",
            "#version 450\nlayout(triangles) in;\nlayout(triangle_strip, max_vertices = 13) out;\n"
            "#include \"penumbra/conservative_raster/conservative_raster.glsl\"\nvoid main() {}\n");
    const std::string e = errorOf([&] { penumbra::gl::compileShader(GL_GEOMETRY_SHADER, "t/no_hook.geom.glsl", {}, lib); });
    INFO(e);
    CHECK(contains(e, "PENUMBRA_CONSERVATIVE_EMIT_VERTEX"));
}

TEST_SUITE("stress") {
    TEST_CASE("stress: 10^6 random triangles per variant, 0 missed pixels") {
        context();
        const uint32_t seed = testSeed();
        const size_t count = defaultCount(1000000);
        MESSAGE("seed ", seed, ", ", count, " triangles per variant");
        for (ConservativeVariant variant : {ConservativeVariant::Fixed6, ConservativeVariant::Exact}) {
            const auto start = std::chrono::steady_clock::now();
            CoverageStats stats = runRandom(variant, seed, count, glm::ivec4(3, 5, 32, 32), glm::ivec2(40, 40));
            MESSAGE(stats.summary(penumbra::conservativeVariantName(variant), seed), "\n  (", seconds(start), " s)");
            requireClean(stats);
        }
    }

    TEST_CASE("stress: the box's pixel range holds every required pixel, 10^6 triangles") {
        boxPixelsSweep(testSeed(), int(defaultCount(1000000) / 6 + 1));
    }

    TEST_CASE("stress: 2 * 10^5 triangles per variant in a 16384^2 viewport and at 1e5 world units") {
        context();
        const uint32_t seed = testSeed();
        MESSAGE("seed ", seed);
        largeViewport(seed, defaultCount(1000000) / 5);
        farFromOrigin(seed, defaultCount(1000000) / 5);
    }
}
