// light_lut on the GPU: LightLutGenerator's tables byte-identical to generateLightLut (ball and
// disk samples x resolutions 16, 32 (64 in the stress suite) x seed and certified mode, octahedral,
// plus a two-angle and a non-symmetric case, plus forced chunking: one table per dispatch, slabs
// of distance cells, a narrow grid), poisoned outputs with guard words; the GLSL lookups of
// lookup.glsl through their hooks (tests/shaders/light_lut/lookup_test.comp.glsl) against the CPU
// twins bit for bit over random planes (lightLutLookup<float>, exactBehind<float>, lutCombine,
// lutResolve, the rotation), certified-resolved == exact == exactBehindOracle (fp64 on the same
// float inputs; issue 41 item 10's plane on the GPU); the RGBA32UI texture helper; setup
// errors and the per-call Status of every misuse; a missing hook failing to compile with its name.
//
// Bit identity of the lookups needs correctly rounded float +, *, /, sqrt (llvmpipe); the table
// identity needs correctly rounded fp64 + and * (GLSL promises no more than single precision for
// doubles). Both are the bitwise tier (support/gl_test_support.hpp); the portable tier asserts that
// chunking and moved bindings reproduce the driver's own unchunked table, at most 0.1% of table words
// and 1% of lookups differ from the twins, and certified + resolve == exact. The two-angle lookup
// calls acos/atan, whose GLSL precision is unspecified: its cells are compared and the mismatch
// fraction is printed, and only the exactness of certified + resolve is asserted.
//
// PENUMBRA_ASSERT counts instead of aborting, so the misuse cases run in Debug builds too.
namespace {
int g_lut_test_asserts = 0;
}
#define PENUMBRA_ASSERT(cond) ((cond) ? void(0) : void(++g_lut_test_asserts))

#include "shader_catalog.hpp"
#include "support/gl_test_support.hpp"
#include "support/test_support.hpp"

#include <penumbra/detail/dispatch.hpp>
#include <penumbra/gl/light_lut.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/shader.hpp>
#include <penumbra/light_lut.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <bitset>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

using glm::dvec3;
using glm::dvec4;
using penumbra::Status;
using penumbra::test::contains;
using penumbra::test::context;
using penumbra::test::errorOf;

namespace {

constexpr uint32_t kPoison = 0xDEADBEEFu;

std::vector<dvec3> ballSets(uint32_t n, uint32_t sets, uint32_t seed) {
    std::vector<dvec3> all;
    for (uint32_t s = 0; s < sets; ++s) {
        const std::vector<dvec3> one = penumbra::reference::sphereLightSamples(dvec3(0.0), 0.999, n, seed + s);
        all.insert(all.end(), one.begin(), one.end());
    }
    return all;
}

std::vector<dvec3> diskSets(uint32_t n, uint32_t sets, uint32_t seed) {
    std::vector<dvec3> all;
    for (uint32_t s = 0; s < sets; ++s) {
        const std::vector<dvec3> one =
            penumbra::reference::diskLightSamples(dvec3(0.0), dvec3(0, 0, 1), 0.999, n, seed + s);
        all.insert(all.end(), one.begin(), one.end());
    }
    return all;
}

penumbra::LightLutOptions lutOptions(uint32_t resolution, bool certified,
                                     penumbra::LutNormalMapping mapping = penumbra::LutNormalMapping::Octahedral,
                                     bool symmetric = true) {
    penumbra::LightLutOptions o;
    o.resolution = resolution;
    o.certified = certified;
    o.mapping = mapping;
    o.symmetric = symmetric;
    return o;
}

std::string firstMismatch(const std::vector<uint32_t>& got, const std::vector<uint32_t>& want) {
    return penumbra::test::firstMismatch(got, want, 4, "texel");
}

/// Generates on the GPU into a poisoned buffer at a nonzero aligned offset with guard words
/// around, reads back, checks the guards, and returns the LUT words.
std::vector<uint32_t> gpuLut(penumbra::LightLutGenerator& generator, const penumbra::LightLutSetup& setup) {
    const uint64_t align = generator.tableAlignment();
    const uint64_t offset = std::max<uint64_t>(align, 256);
    const uint64_t bytes = setup.tableBytes();
    penumbra::gl::Buffer buffer(offset + bytes + 256);
    buffer.fill(kPoison);
    const penumbra::BufferRange table{buffer.id(), offset, bytes};
    generator.reserve(setup);
    generator.validate(setup, table);
    REQUIRE(generator.generate(setup, table) == Status::Ok);
    const std::vector<uint32_t> words = penumbra::readLightLut(setup, table);
    const auto before = buffer.download<uint32_t>(0, offset / 4);
    const auto after = buffer.download<uint32_t>(offset + bytes, 64);
    for (uint32_t w : before) REQUIRE(w == kPoison);
    for (uint32_t w : after) REQUIRE(w == kPoison);
    return words;
}

struct GenCase {
    std::string name;
    std::vector<dvec3> samples;
    uint32_t n;
    penumbra::LightLutOptions options;
};

size_t differingWords(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
    if (a.size() != b.size()) return std::max(a.size(), b.size());
    size_t count = 0;
    for (size_t i = 0; i < a.size(); ++i) count += a[i] != b[i];
    return count;
}

void checkIdentical(penumbra::LightLutGenerator& generator, const GenCase& c) {
    INFO(c.name);
    const penumbra::LightLutSetup setup = penumbra::lightLutSetup(c.samples, c.n, c.options);
    const std::vector<uint32_t> cpu = penumbra::generateLightLut(setup);
    const std::vector<uint32_t> gpu = gpuLut(generator, setup);
    const std::string mismatch = firstMismatch(gpu, cpu);
    INFO(mismatch);
    PENUMBRA_CHECK_BITWISE("light LUT table GPU == generateLightLut byte for byte", mismatch.empty());
    CHECK(differingWords(gpu, cpu) * 1000 <= cpu.size());
    if (mismatch.empty()) {
        MESSAGE(c.name, ": ", setup.tableBytes(), " bytes, ", generator.dispatches().size(),
                " dispatch(es), GPU == CPU byte for byte");
    }
}

std::vector<GenCase> generationCases(const std::vector<uint32_t>& resolutions) {
    using M = penumbra::LutNormalMapping;
    std::vector<GenCase> cases;
    for (uint32_t r : resolutions)
        for (bool certified : {false, true}) {
            const std::string mode = certified ? " certified" : " seed";
            cases.push_back({"ball 160 x 2 sets oct R" + std::to_string(r) + mode, ballSets(160, 2, 7), 160,
                             lutOptions(r, certified)});
            cases.push_back({"disk 128 oct R" + std::to_string(r) + mode, diskSets(128, 1, 3), 128,
                             lutOptions(r, certified)});
        }
    for (bool certified : {false, true}) {
        const std::string mode = certified ? " certified" : " seed";
        cases.push_back({"ball 256 two angles R16" + mode, ballSets(256, 1, 11), 256, lutOptions(16, certified, M::Spherical)});
        cases.push_back({"disk 96 oct non-symmetric R16" + mode, diskSets(96, 1, 5), 96,
                         lutOptions(16, certified, M::Octahedral, false)});
    }
    return cases;
}

// The lookup test kernel (tests/shaders/light_lut/lookup_test.comp.glsl) over planes x tables.
class LookupKernel {
public:
    explicit LookupKernel(int mode) {
        penumbra::ShaderLibrary lib = penumbra::test::catalogLibrary();
        program_ = penumbra::gl::buildComputeProgram("light_lut/lookup_test.comp.glsl",
                                                     {{"PENUMBRA_LUT_TEST_MODE", std::to_string(mode)}}, lib);
        outputs_ = mode == 0 ? 9 : 1;
    }
    /// Runs over `planes` and every table; returns outputs_ uvec4 per (plane, table).
    std::vector<glm::uvec4> run(const penumbra::LightLutSetup& setup, GLuint lut, const std::vector<glm::vec4>& planes,
                                const std::vector<glm::vec2>& rotations) const {
        std::vector<glm::vec4> samples(setup.samples.size());
        for (size_t i = 0; i < samples.size(); ++i) samples[i] = glm::vec4(glm::vec3(setup.samples[i]), 0.0f);
        penumbra::gl::Buffer params(sizeof setup.params, &setup.params), sample_buffer = penumbra::gl::Buffer::fromVector(samples),
            plane_buffer = penumbra::gl::Buffer::fromVector(planes), rotation_buffer = penumbra::gl::Buffer::fromVector(rotations);
        const uint64_t entries = planes.size() * setup.params.tables;
        penumbra::gl::Buffer results(entries * outputs_ * 16);
        results.fill(kPoison);
        glBindBufferBase(GL_UNIFORM_BUFFER, 0, params.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, lut);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, sample_buffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, plane_buffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, rotation_buffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, results.id());
        program_.use();
        glUniform1ui(0, static_cast<GLuint>(planes.size()));
        glUniform1ui(1, setup.params.tables);
        const penumbra::detail::DispatchGrid grid = penumbra::detail::foldDispatch(penumbra::detail::divUp(entries, 64));
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        glDispatchCompute(grid.x, grid.y, 1);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        return results.download<glm::uvec4>();
    }

private:
    penumbra::gl::Program program_;
    int outputs_ = 1;
};

penumbra::LutMask mask(const glm::uvec4& v) { return {v.x, v.y, v.z, v.w}; }

/// Random planes (unit normal, through a point within 1.5 of the centre), and special ones:
/// trivial, bad, axis-aligned, through the centre, scaled normals, signed zeros.
std::vector<glm::vec4> testPlanes(std::mt19937_64& rng, size_t count) {
    std::normal_distribution<double> normal;
    std::uniform_real_distribution<double> uniform(-1.5, 1.5);
    std::vector<glm::vec4> planes;
    const float nan = std::nanf(""), inf = INFINITY;
    for (const glm::vec4& p :
         {glm::vec4(0, 0, 1, 1), glm::vec4(0, 0, 1, -1), glm::vec4(0, 0, 2, 2.5f), glm::vec4(0, 0, -3, -2),
          glm::vec4(nan, 0, 1, 0), glm::vec4(0, 0, 1, nan), glm::vec4(0, 0, 0, -0.5f), glm::vec4(inf, 0, 0, 0),
          glm::vec4(1, 0, 0, 0), glm::vec4(-1, 0, 0, 0), glm::vec4(0, 1, 0, 0.25f), glm::vec4(0, -1, 0, -0.25f),
          glm::vec4(0, 0, 1, 0), glm::vec4(0, 0, -1, 0), glm::vec4(-0.0f, -0.0f, -1, -0.0f), glm::vec4(1, 1, 0, 0.3f),
          glm::vec4(1, -1, 0, -0.3f), glm::vec4(0.5f, 0.5f, -0.5f, 0.1f), glm::vec4(1e-30f, 0, 0, 0),
          glm::vec4(3e19f, 3e19f, 3e19f, 1)})
        planes.push_back(p);
    while (planes.size() < count) {
        dvec3 n;
        do n = dvec3(normal(rng), normal(rng), normal(rng)); while (glm::dot(n, n) < 1e-12);
        n = glm::normalize(n);
        const dvec3 p(uniform(rng), uniform(rng), uniform(rng));
        // Every 8th plane with a non-unit normal (the lookup divides by |n|).
        const double scale = planes.size() % 8 == 0 ? 0.25 + 3.0 * (uniform(rng) + 1.5) / 3.0 : 1.0;
        planes.push_back(glm::vec4(dvec4(n * scale, -glm::dot(n, p) * scale)));
    }
    return planes;
}

std::vector<glm::vec2> testRotations(std::mt19937_64& rng, size_t count) {
    std::uniform_real_distribution<float> angle(0.0f, 6.2831853f);
    std::vector<glm::vec2> r(count);
    for (auto& v : r) {
        const float a = angle(rng);
        v = glm::vec2(std::cos(a), std::sin(a));
    }
    return r;
}

/// CPU twin of penumbraLutRotate (products rounded, no FMA).
glm::vec4 rotateTwin(const glm::vec4& p, float c, float s) {
    using penumbra::detail::mulRounded;
    return glm::vec4(mulRounded(p.x, c) + mulRounded(p.y, s), mulRounded(p.y, c) - mulRounded(p.x, s), p.z, p.w);
}

struct LookupTally {
    uint64_t entries = 0, bad_planes = 0, behind = 0, certain = 0, uncertain = 0, exact = 0, resolve = 0, combine = 0, locate = 0,
             rotate = 0, resolved_not_exact = 0, resolved_not_oracle = 0, exact_not_oracle = 0;
};

LookupTally compareLookups(const penumbra::LightLutSetup& setup, const std::vector<uint32_t>& lut,
                           const std::vector<glm::vec4>& planes, const std::vector<glm::vec2>& rotations,
                           const std::vector<glm::uvec4>& gpu) {
    LookupTally t;
    const uint32_t tables = setup.params.tables;
    for (size_t k = 0; k < planes.size(); ++k)
        for (uint32_t table = 0; table < tables; ++table) {
            const glm::uvec4* g = &gpu[9 * (k * tables + table)];
            const glm::vec4& plane = planes[k];
            const penumbra::LutAnswer a = penumbra::lightLutLookup(setup.params, lut.data(), table, plane);
            const penumbra::LutCertain c = penumbra::lutCertain(a);
            const penumbra::LutMask exact = penumbra::exactBehind(setup, table, plane);
            const penumbra::LutMask resolved = penumbra::lutResolve(setup, table, c, plane);
            const glm::vec4& next = planes[(k + 1) % planes.size()];
            const penumbra::LutCertain c2 = penumbra::lutCertain(penumbra::lightLutLookup(setup.params, lut.data(), table, next));
            const penumbra::LutCertain both = penumbra::lutCombine(c, c2);
            const penumbra::LutCell cell = penumbra::lightLutLocate(setup.params, plane);
            const glm::vec4 rotated = rotateTwin(plane, rotations[k].x, rotations[k].y);
            ++t.entries;
            t.behind += mask(g[0]) != a.centre;
            t.certain += mask(g[1]) != c.behind;
            t.uncertain += mask(g[2]) != c.uncertain;
            t.exact += mask(g[3]) != exact;
            t.resolve += mask(g[4]) != resolved;
            t.combine += mask(g[5]) != both.behind || mask(g[6]) != both.uncertain;
            t.locate += g[7] != glm::uvec4(cell.texel, cell.flip ? 1u : 0u, uint32_t(cell.trivial + 1), 0u);
            t.rotate += std::memcmp(&g[8], &rotated, 16) != 0;
            // Planes with a non-finite value, or whose float |n| is 0 or overflows, have the
            // documented empty mask (not the exact one).
            const float len = std::sqrt(penumbra::detail::dotRounded(glm::vec3(plane), glm::vec3(plane)));
            if (!(len > 0.0f) || !std::isfinite(len) || !std::isfinite(plane.w)) {
                t.bad_planes += table == 0;
                continue;
            }
            t.resolved_not_exact += mask(g[4]) != mask(g[3]);
            // The fp64 oracle on the same float samples and plane the GPU used (issue 41 item 10).
            const penumbra::LutMask oracle = penumbra::exactBehindOracle(setup, table, plane);
            t.resolved_not_oracle += mask(g[4]) != oracle;
            t.exact_not_oracle += mask(g[3]) != oracle;
        }
    return t;
}

}  // namespace

TEST_CASE("LightLutGenerator: GPU tables byte-identical to generateLightLut (2 shapes x R 16, 32 x seed, certified; two angles; non-symmetric)") {
    context();
    penumbra::LightLutGenerator generator;
    for (const GenCase& c : generationCases({16, 32})) checkIdentical(generator, c);
}

TEST_CASE("LightLutGenerator: forced chunking (table windows, distance slabs, narrow grids) stays byte-identical") {
    context();
    const penumbra::LightLutSetup setup = penumbra::lightLutSetup(ballSets(160, 2, 21), 160, lutOptions(32, true));
    const std::vector<uint32_t> cpu = penumbra::generateLightLut(setup);
    penumbra::LightLutGenerator unchunked;
    const std::vector<uint32_t> gpu_unchunked = gpuLut(unchunked, setup);
    const uint64_t table_bytes = uint64_t(setup.params.texels_per_table) * 16, slab = 32ull * 32 * 16;
    struct Limits {
        const char* name;
        penumbra::LightLutGeneratorOptions options;
        size_t min_dispatches;
    };
    const Limits limits[] = {
        {"one table per window", {table_bytes, 0, 0}, 4},
        {"two tables per window", {2 * table_bytes + 5, 0, 0}, 2},
        {"slabs of 5 distance cells", {5 * slab + 100, 0, 0}, 4 * 7},
        {"slabs of 3, grid 7 x 65535", {3 * slab, 7, 0}, 4 * 11},
        {"grid 512 x 2 groups: one table per dispatch", {0, 512, 2}, 4},
    };
    for (const Limits& l : limits) {
        INFO(std::string(l.name));
        penumbra::LightLutGenerator generator(penumbra::ShaderLibrary::embedded(), {}, l.options);
        const std::vector<uint32_t> gpu = gpuLut(generator, setup);
        CHECK(generator.dispatches().size() >= l.min_dispatches);
        for (const penumbra::LightLutDispatch& d : generator.dispatches()) {
            CHECK(d.grid_x >= 1);
            CHECK(uint64_t(d.grid_x) * d.grid_y >= d.groups);
            if (l.options.max_groups_x) CHECK(d.grid_x <= l.options.max_groups_x);
            if (l.options.max_groups_y) CHECK(d.grid_y <= l.options.max_groups_y);
        }
        const std::string mismatch = firstMismatch(gpu, cpu);
        INFO(mismatch);
        PENUMBRA_CHECK_BITWISE("light LUT chunked table GPU == generateLightLut byte for byte", mismatch.empty());
        CHECK(firstMismatch(gpu, gpu_unchunked).empty());  // chunking changes no texel's arithmetic
        MESSAGE(std::string(l.name), ": ", generator.dispatches().size(), " dispatches, identical: ", mismatch.empty());
    }
}

TEST_CASE("LightLutGenerator: the default bindings can move; moved-from generators refuse") {
    context();
    const penumbra::LightLutSetup setup = penumbra::lightLutSetup(diskSets(64, 1, 1), 64, lutOptions(16, true));
    penumbra::LightLutBindings bindings;
    bindings.samples = 7;
    bindings.normal_cells = 6;
    bindings.distance_cells = 5;
    bindings.table = 2;
    bindings.uncertain = 0;
    bindings.params = 3;
    penumbra::LightLutGenerator default_bindings;
    const std::vector<uint32_t> want = gpuLut(default_bindings, setup);
    penumbra::LightLutGenerator generator(penumbra::ShaderLibrary::embedded(), bindings);
    CHECK(firstMismatch(gpuLut(generator, setup), want).empty());
    penumbra::LightLutGenerator moved = std::move(generator);
    CHECK(firstMismatch(gpuLut(moved, setup), want).empty());
    PENUMBRA_CHECK_BITWISE("light LUT table (moved bindings) GPU == generateLightLut byte for byte",
                           firstMismatch(want, penumbra::generateLightLut(setup)).empty());
    penumbra::gl::Buffer buffer(setup.tableBytes());
    g_lut_test_asserts = 0;
    CHECK(generator.generate(setup, {buffer.id(), 0, buffer.size()}) == Status::NotReserved);  // NOLINT: moved-from
    CHECK(g_lut_test_asserts == 1);
}

TEST_CASE("LightLutGenerator: the RGBA32UI 3D texture helper copies one table") {
    context();
    const penumbra::LightLutSetup setup = penumbra::lightLutSetup(ballSets(160, 1, 9), 160, lutOptions(16, true));
    penumbra::LightLutGenerator generator;
    penumbra::gl::Buffer buffer(setup.tableBytes());
    const penumbra::BufferRange table{buffer.id(), 0, buffer.size()};
    generator.reserve(setup);
    REQUIRE(generator.generate(setup, table) == Status::Ok);
    const std::vector<uint32_t> cpu = penumbra::readLightLut(setup, table);  // what the helper must copy
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);  // engine state the helper must restore
    for (const bool uncertain : {false, true}) {
        penumbra::gl::Texture texture = penumbra::createLightLutTexture(setup);
        penumbra::uploadLightLutTexture(texture.id(), setup, table, 1, uncertain);
        std::vector<uint32_t> texels(setup.params.texels_per_table * 4);
        glGetTextureImage(texture.id(), 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT, static_cast<GLsizei>(texels.size() * 4),
                          texels.data());
        const uint64_t first = ((uncertain ? setup.params.uncertain_offset : 0u) + setup.params.texels_per_table) * 4ull;
        const std::vector<uint32_t> want(cpu.begin() + static_cast<std::ptrdiff_t>(first),
                                         cpu.begin() + static_cast<std::ptrdiff_t>(first + texels.size()));
        CHECK(firstMismatch(texels, want).empty());
    }
    CHECK(penumbra::gl::getInteger(GL_UNPACK_ALIGNMENT) == 1);
    CHECK(penumbra::gl::getInteger(GL_PIXEL_UNPACK_BUFFER_BINDING) == 0);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    CHECK(contains(errorOf([&] { penumbra::uploadLightLutTexture(0, setup, table, 2); }), "table 2 of 2"));
}

namespace {

void lookupIdentity(size_t count) {
    context();
    const uint32_t seed = penumbra::test::testSeed();
    std::mt19937_64 rng(seed);
    const std::vector<glm::vec4> planes = testPlanes(rng, count);
    const std::vector<glm::vec2> rotations = testRotations(rng, count);
    const LookupKernel kernel(0);
    penumbra::LightLutGenerator generator;
    using M = penumbra::LutNormalMapping;
    struct Case {
        const char* name;
        std::vector<dvec3> samples;
        uint32_t n;
        penumbra::LightLutOptions options;
    };
    const std::vector<Case> cases = {
        {"ball 160 oct sym R32 certified", ballSets(160, 1, 31), 160, lutOptions(32, true)},
        {"disk 128 oct sym R16 certified", diskSets(128, 1, 4), 128, lutOptions(16, true)},
        {"ball 128 oct non-symmetric R16 certified", ballSets(128, 1, 5), 128, lutOptions(16, true, M::Octahedral, false)},
        {"ball 128 oct sym R32 seed", ballSets(128, 1, 6), 128, lutOptions(32, false)},
        {"ball 128 two angles R32 certified", ballSets(128, 1, 8), 128, lutOptions(32, true, M::Spherical)},
    };
    for (const Case& c : cases) {
        INFO(std::string(c.name));
        const penumbra::LightLutSetup setup = penumbra::lightLutSetup(c.samples, c.n, c.options);
        const std::vector<uint32_t> lut = penumbra::generateLightLut(setup);
        penumbra::gl::Buffer lut_buffer = penumbra::gl::Buffer::fromVector(lut);
        const std::vector<glm::uvec4> gpu = kernel.run(setup, lut_buffer.id(), planes, rotations);
        const LookupTally t = compareLookups(setup, lut, planes, rotations, gpu);
        MESSAGE(std::string(c.name), ": ", t.entries, " (plane, table) lookups; GPU != twin: behind ", t.behind, ", certain ",
                t.certain, ", uncertain ", t.uncertain, ", exact ", t.exact, ", resolve ", t.resolve, ", combine ",
                t.combine, ", locate ", t.locate, ", rotate ", t.rotate, "; resolved != exact float ",
                t.resolved_not_exact, "; != fp64 oracle: resolved ", t.resolved_not_oracle, ", exact ", t.exact_not_oracle,
                " (", t.bad_planes, " bad planes excluded)");
        PENUMBRA_CHECK_BITWISE("lookup.glsl exactBehind GPU == CPU twin", t.exact == 0);
        PENUMBRA_CHECK_BITWISE("lookup.glsl penumbraLutRotate GPU == CPU twin", t.rotate == 0);
        CHECK(t.exact * 100 <= t.entries);
        if (c.options.mapping == M::Octahedral) {
            PENUMBRA_CHECK_BITWISE("lookup.glsl locate/lookup/certain/resolve/combine GPU == CPU twins",
                                   (t.locate | t.behind | t.certain | t.uncertain | t.resolve | t.combine) == 0);
            for (uint64_t wrong : {t.locate, t.behind, t.certain, t.uncertain, t.resolve, t.combine}) CHECK(wrong * 100 <= t.entries);
        }
        if (c.options.certified) CHECK(t.resolved_not_exact == 0);
        // The float filter's fallback is fp64: the oracle's verdict where fp64 + and * are IEEE.
        PENUMBRA_CHECK_BITWISE("lookup.glsl penumbraExactBehind == exactBehindOracle", t.exact_not_oracle == 0);
        if (c.options.certified)
            PENUMBRA_CHECK_BITWISE("lookup.glsl penumbraLutResolve == exactBehindOracle", t.resolved_not_oracle == 0);
    }
}

}  // namespace

TEST_CASE("lookup.glsl: GLSL lookups equal the CPU twins bit for bit; certified + resolve is exact") {
    lookupIdentity(20000);
}

TEST_CASE("lookup.glsl: issue 41 item 10's plane: certified + resolve and the exact test give the fp64 oracle's bit") {
    context();
    // BM_LutLookupCertified/64/512's one wrong bit: plane 56000, table 3, bit 31. Exact value on
    // these float inputs -2.4893796357616793e-08 (Python fractions): behind; float rounds it to 0.
    const glm::vec4 plane(-0x1.b5fd3p-1f, -0x1.d51bp-2f, -0x1.eeaf9ep-3f, 0x1.d44ce4p-2f);
    const penumbra::LightLutSetup setup = penumbra::lightLutSetup(
        penumbra::reference::sphereLightSamples(dvec3(0.0), 0.999, 512, 20261201u), 512, lutOptions(64, true));
    REQUIRE(glm::vec3(setup.samples[3 * 128 + 31]) == glm::vec3(0x1.6f1ad4p-2f, 0x1.44ee3p-1f, -0x1.28ef46p-1f));
    // Only the texel this plane reads (table 3) is filled: the whole LUT takes seconds on the CPU.
    const penumbra::LutCell cell = penumbra::lightLutLocate(setup.params, plane);
    REQUIRE(cell.trivial == 0);
    std::vector<uint32_t> words(setup.texelCount() * 4, 0u);
    const penumbra::LutAnswer texel = penumbra::lightLutTexel(setup, 3, cell.texel);
    const uint64_t centre_at = (3ull * setup.params.texels_per_table + cell.texel) * 4;
    std::copy(texel.centre.begin(), texel.centre.end(), words.begin() + static_cast<std::ptrdiff_t>(centre_at));
    std::copy(texel.uncertain.begin(), texel.uncertain.end(),
              words.begin() + static_cast<std::ptrdiff_t>(centre_at + uint64_t(setup.params.uncertain_offset) * 4));
    REQUIRE(((texel.uncertain[0] >> 31) & 1u) == 1u);  // the lookup leaves the sample to the exact test
    penumbra::gl::Buffer lut = penumbra::gl::Buffer::fromVector(words);
    const std::vector<glm::uvec4> gpu = LookupKernel(0).run(setup, lut.id(), {plane}, {glm::vec2(1.0f, 0.0f)});
    const glm::uvec4* g = &gpu[9 * 3];
    const penumbra::LutMask oracle = penumbra::exactBehindOracle(setup, 3, plane);
    CHECK(((oracle[0] >> 31) & 1u) == 1u);
    CHECK(((g[4].x >> 31) & 1u) == 1u);  // penumbraLutResolve
    CHECK(((g[3].x >> 31) & 1u) == 1u);  // penumbraExactBehind
    PENUMBRA_CHECK_BITWISE("lookup.glsl penumbraLutResolve == exactBehindOracle", mask(g[4]) == oracle);
    PENUMBRA_CHECK_BITWISE("lookup.glsl penumbraExactBehind == exactBehindOracle", mask(g[3]) == oracle);
    // The CPU twins agree.
    CHECK(penumbra::lutResolve(setup, 3, penumbra::lutCertain(penumbra::lightLutLookup(setup.params, words.data(), 3, plane)),
                               plane) == oracle);
    CHECK(penumbra::exactBehind(setup, 3, plane) == oracle);
}

TEST_CASE("LightLutGenerator: setup errors and per-call misuse") {
    context();
    const penumbra::LightLutSetup setup = penumbra::lightLutSetup(ballSets(128, 1, 2), 128, lutOptions(16, true));
    const penumbra::LightLutSetup other = penumbra::lightLutSetup(ballSets(128, 1, 2), 128, lutOptions(18, true));
    const char* f = "LightLutGenerator";
    CAPTURE(f);
    penumbra::LightLutGenerator generator;
    penumbra::gl::Buffer buffer(setup.tableBytes() + 1024);
    const penumbra::BufferRange table{buffer.id(), 0, setup.tableBytes()};
    g_lut_test_asserts = 0;
    // Before reserve(): NotReserved, and validate() names the missing reserve.
    CHECK(generator.generate(setup, table) == Status::NotReserved);
    CHECK(contains(errorOf([&] { generator.validate(setup, table); }), "call reserve(setup)"));
    generator.reserve(setup);
    generator.validate(setup, table);
    // Range too small / null.
    CHECK(generator.generate(setup, {buffer.id(), 0, setup.tableBytes() - 16}) == Status::RangeTooSmall);
    CHECK(generator.generate(setup, {0, 0, setup.tableBytes()}) == Status::RangeTooSmall);
    CHECK(contains(errorOf([&] { generator.validate(setup, {buffer.id(), 0, setup.tableBytes() - 16}); }),
                   "needs " + std::to_string(setup.tableBytes())));
    // Misaligned offset.
    const uint64_t align = generator.tableAlignment();
    if (align > 1) {
        CHECK(generator.generate(setup, {buffer.id(), align / 2, setup.tableBytes()}) == Status::Misaligned);
        CHECK(contains(errorOf([&] { generator.validate(setup, {buffer.id(), align / 2, setup.tableBytes()}); }),
                       "is not a multiple of"));
    }
    // Past the buffer's end, not a buffer.
    CHECK(contains(errorOf([&] { generator.validate(setup, {buffer.id(), 1024, setup.tableBytes() + 16}); }),
                   "exceeds buffer"));
    CHECK(contains(errorOf([&] { generator.validate(setup, {987654u, 0, setup.tableBytes()}); }), "is not a buffer object"));
    // Another setup than the reserved one.
    CHECK(generator.generate(other, table) == Status::NotReserved);
    CHECK(contains(errorOf([&] { generator.validate(other, table); }), "not the one reserve()"));
    CHECK(g_lut_test_asserts == 4 + (align > 1 ? 1 : 0));
    // A setup whose arrays do not match its parameters.
    penumbra::LightLutSetup broken = setup;
    broken.samples.pop_back();
    CHECK(contains(errorOf([&] { generator.reserve(broken); }), "127 samples"));
    broken = setup;
    broken.distance_cells.resize(3);
    CHECK(contains(errorOf([&] { generator.reserve(broken); }), "3 distance cells"));
    // Bindings.
    penumbra::LightLutBindings same;
    same.uncertain = same.table;
    CHECK(contains(errorOf([&] { penumbra::LightLutGenerator g(penumbra::ShaderLibrary::embedded(), same); }),
                   "uncertain and table are both"));
    penumbra::LightLutBindings far;
    far.params = 100000;
    CHECK(contains(errorOf([&] { penumbra::LightLutGenerator g(penumbra::ShaderLibrary::embedded(), far); }),
                   "GL_MAX_UNIFORM_BUFFER_BINDINGS"));
    // Limits too small for one slice.
    penumbra::LightLutGeneratorOptions tiny;
    tiny.max_binding_bytes = 1000;
    penumbra::LightLutGenerator small(penumbra::ShaderLibrary::embedded(), {}, tiny);
    CHECK(contains(errorOf([&] { small.reserve(setup); }), "cannot hold one slice"));
    // readLightLut of a short range.
    CHECK(contains(errorOf([&] { penumbra::readLightLut(setup, {buffer.id(), 0, 16}); }), "the LUT has"));
}

TEST_CASE("lookup.glsl: a missing hook is a compile error naming it") {
    context();
    for (const char* missing : {"PENUMBRA_LUT_PARAMS", "PENUMBRA_LUT_LOAD", "PENUMBRA_LUT_SAMPLE"}) {
        std::string text = "layout(local_size_x = 1) in;\n#include \"penumbra/light_lut/light_lut_shared.h\"\n";
        if (std::string(missing) != "PENUMBRA_LUT_PARAMS") text += "#define PENUMBRA_LUT_PARAMS PenumbraLutParams(16u,16u,1u,1u,128u,1u,0u,1u,4096u,0u,0u,0u)\n";
        if (std::string(missing) != "PENUMBRA_LUT_LOAD") text += "#define PENUMBRA_LUT_LOAD(index) uvec4(index)\n";
        if (std::string(missing) != "PENUMBRA_LUT_SAMPLE") text += "#define PENUMBRA_LUT_SAMPLE(table, bit) vec3(0.0)\n";
        text += "#include \"penumbra/light_lut/lookup.glsl\"\nvoid main() {}\n";
        penumbra::ShaderLibrary lib = penumbra::ShaderLibrary::embedded();
        lib.add("test/lut_hook.comp.glsl", text);
        const std::string error = errorOf([&] { penumbra::gl::buildComputeProgram("test/lut_hook.comp.glsl", {}, lib); });
        CAPTURE(error);
        CHECK(contains(error, missing));
    }
}

TEST_SUITE("stress") {
    TEST_CASE("lookup.glsl: GLSL lookups equal the CPU twins, 200 000 planes") { lookupIdentity(200000); }

    TEST_CASE("LightLutGenerator: GPU tables byte-identical at R 64") {
        context();
        penumbra::LightLutGenerator generator;
        std::vector<GenCase> cases;
        for (bool certified : {false, true}) {
            cases.push_back({std::string("ball 160 x 2 sets oct R64") + (certified ? " certified" : " seed"),
                             ballSets(160, 2, 7), 160, lutOptions(64, certified)});
            cases.push_back({std::string("disk 128 oct R64") + (certified ? " certified" : " seed"), diskSets(128, 1, 3),
                             128, lutOptions(64, certified)});
        }
        for (const GenCase& c : cases) checkIdentical(generator, c);
    }
}
