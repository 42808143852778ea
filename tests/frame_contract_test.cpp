// The per-frame contract (issue 7; docs/design.md, convention 2), recorded: after warm-up, every GL
// call made inside Scanner::scan, SampleListBuilder::build, AliasFreeHardShadows::run (buffer
// and depth input, with the GPU fit and statistics on), LightLutGenerator::generate,
// DeepShadowMapBuilder::build and ShadowEdgeStencil::run / writeSampleBuffer / resolve (the soft
// pipeline and the light volume have theirs in their own tests) is logged through glad's debug loader
// (support/gl_audit.hpp) and the heap is counted (support/alloc_counter.hpp): 0 queries (glGet*,
// glIs*, glCheck*Status), 0 glGetError, 0 read-backs, 0 maps, 0 glFinish / fence waits, 0 heap
// allocations. A queued engine error survives each call. The same holds for the conservative
// spill helpers. Holds on any driver: it is about which calls are made, not their results.
#include "support/alloc_counter.hpp"
#include "support/gl_audit.hpp"
#include "support/gl_test_support.hpp"
#include "support/gl_world.hpp"

#include <penumbra/gl/conservative_raster.hpp>
#include <penumbra/gl/deep_shadow_map.hpp>
#include <penumbra/gl/light_lut.hpp>
#include <penumbra/gl/pipelines/alias_free_hard.hpp>
#include <penumbra/gl/sample_lists.hpp>
#include <penumbra/gl/scan.hpp>
#include <penumbra/gl/shadow_edge_stencil.hpp>
#include <penumbra/scene/gl_scene.hpp>
#include <penumbra/scene/scene.hpp>

#include <doctest/doctest.h>

#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace {

using penumbra::Status;
using penumbra::test::AllocationCounter;
using penumbra::test::context;
using penumbra::test::GlAudit;

struct Recorded {
    std::string report;
    size_t calls = 0, queries = 0, error_checks = 0, read_backs = 0, maps = 0, sync_waits = 0, allocations = 0;
    size_t driver_allocations = 0;  // inside GL calls: the driver's (support/driver_call.hpp)
    Status status = Status::Ok;
};

// Warm-up call, then the recorded one. `f` returns the per-frame call's Status.
Recorded record(const std::function<Status()>& f) {
    f();
    glFinish();
    GlAudit audit;
    AllocationCounter heap;
    Recorded r;
    audit.start();
    heap.start();
    r.status = f();
    heap.stop();
    audit.stop();
    r.report = audit.report();
    r.calls = audit.calls();
    r.queries = audit.queries();
    r.error_checks = audit.errorChecks();
    r.read_backs = audit.readBacks();
    r.maps = audit.maps();
    r.sync_waits = audit.syncWaits();
    r.allocations = heap.allocations();
    r.driver_allocations = heap.driverAllocations();
    return r;
}

void checkContract(const Recorded& r, const std::string& what) {
    INFO(what);
    INFO(r.report);
    CHECK(r.status == Status::Ok);
    CHECK(r.calls > 0);
    CHECK(r.queries == 0);
    CHECK(r.error_checks == 0);
    CHECK(r.read_backs == 0);
    CHECK(r.maps == 0);
    CHECK(r.sync_waits == 0);
    CHECK(r.allocations == 0);
    MESSAGE(what, ": ", r.calls, " GL calls, 0 queries, 0 glGetError, 0 read-backs/maps/waits, 0 allocations (",
            r.driver_allocations, " inside GL calls, the driver's)");
}

/// Queues GL_INVALID_ENUM as an engine would by mistake; the executor must leave it queued.
void queueEngineError() { glBindBuffer(0xDEADu, 0); }

penumbra::BufferRange range(const penumbra::gl::Buffer& b) { return {b.id(), 0, b.size()}; }

using World = penumbra::test::GlWorld;

}  // namespace

TEST_CASE("Scanner::scan: no query, read-back, wait or allocation per frame; the engine's error survives") {
    context();
    const uint64_t n = (1u << 20) + 3;
    std::vector<uint32_t> values(n, 1u);
    auto in = penumbra::gl::Buffer::fromVector(values);
    penumbra::gl::Buffer out(n * 4);
    penumbra::Scanner scanner;
    scanner.reserve(n);
    scanner.validate(range(in), range(out), n);
    checkContract(record([&] { return scanner.exclusive(range(in), range(out), n); }), "Scanner::exclusive 2^20+3");
    queueEngineError();
    scanner.exclusive(range(in), range(out), n);
    CHECK(glGetError() == GL_INVALID_ENUM);
}

TEST_CASE("SampleListBuilder::build (fit + statistics on the GPU): buffer and depth input") {
    context();
    World w;
    const penumbra::SampleListsSetup setup = penumbra::sampleListsSetup(96, 72, w.samples());
    penumbra::gl::Buffer counts(setup.counts_bytes), offsets(setup.offsets_bytes), positions(setup.list_positions_bytes),
        ids(setup.list_ids_bytes), slots(setup.sample_slots_bytes), texels(setup.sample_texels_bytes),
        header(setup.header_bytes), frustum(sizeof(penumbra::SampleListsFrustum));
    const penumbra::SampleListsBuffers out{range(counts), range(offsets), range(positions), range(ids),
                                           range(slots),  range(texels),  range(header),    range(frustum)};
    penumbra::SampleListBuilder builder;
    builder.reserve(setup);
    builder.validate(setup, w.bufferInput(), out);
    builder.validate(setup, w.depthInput(), out);
    penumbra::SampleListsBuild build;
    build.fit_frustum = true;
    build.statistics = true;
    checkContract(record([&] { return builder.build(setup, w.light, w.bufferInput(), out, {}, build); }),
                  "SampleListBuilder::build, buffer input");
    checkContract(record([&] { return builder.build(setup, w.light, w.depthInput(), out, {}, build); }),
                  "SampleListBuilder::build, depth input");
    queueEngineError();
    builder.build(setup, w.light, w.bufferInput(), out, {}, build);
    CHECK(glGetError() == GL_INVALID_ENUM);
    // Misuse detected without GL: a Status and not one GL call.
    penumbra::SampleListsBuffers small = out;
    small.counts.size = 4;
    const Recorded misuse = record([&] { return builder.build(setup, w.light, w.bufferInput(), small); });
    CHECK(misuse.status == Status::RangeTooSmall);
    CHECK(misuse.calls == 0);
    CHECK(misuse.allocations == 0);
}

TEST_CASE("AliasFreeHardShadows::run: buffer and depth input, exact and fast; Fixed-6 two-pass and Exact variant") {
    context();
    World w;
    auto draw = [&](penumbra::CasterClass cls) { w.drawClass(cls); };
    const penumbra::AliasFreeHardShadows::DrawCasters casters = draw;  // built once, outside the frame
    // Default Fixed-6 (two-pass light pass: spill reset, direct pass at max_vertices 6, indirect
    // spill draw, GPU copy of the spill figures) in exact and fast precision, and the Exact variant.
    for (int config = 0; config < 3; ++config) {
        const auto precision = config == 1 ? penumbra::AfhPrecision::Fast : penumbra::AfhPrecision::Exact;
        penumbra::AliasFreeHardOptions o;
        o.grid_width = 96;
        o.grid_height = 72;
        o.precision = precision;
        if (config == 2) o.variant = penumbra::ConservativeVariant::Exact;
        penumbra::AliasFreeHardShadows pipeline(o);
        CHECK(pipeline.twoPass() == (config != 2));
        pipeline.reserve(w.samples());
        pipeline.validate(w.bufferInput(), w.samples());
        pipeline.validate(w.depthInput());
        const char* name = config == 0 ? "run, fixed6 two-pass, exact" : config == 1 ? "run, fixed6 two-pass, fast"
                                                                                   : "run, exact variant, exact";
        checkContract(record([&] { return pipeline.run(w.bufferInput(), w.samples(), w.light, casters); }),
                      std::string(name) + ", buffer input");
        checkContract(record([&] { return pipeline.run(w.depthInput(), w.light, casters); }),
                      std::string(name) + ", depth input");
        queueEngineError();
        pipeline.run(w.bufferInput(), w.samples(), w.light, casters);
        CHECK(glGetError() == GL_INVALID_ENUM);
        const Recorded misuse = record([&] { return pipeline.run(w.bufferInput(), w.samples() + 1, w.light, casters); });
        CHECK(misuse.status == Status::NotReserved);
        CHECK(misuse.calls == 0);
    }
}

TEST_CASE("AliasFreeHardShadows::run, compute light pass: the contract, and no draw, query, stencil or framebuffer call") {
    context();
    World w;
    const std::vector<penumbra::CasterBuffer>& casters = w.gpu.casterBuffers();
    const uint32_t ranges = static_cast<uint32_t>(casters.size());
    for (const bool depth : {false, true}) {
        CAPTURE(depth);
        penumbra::AliasFreeHardOptions o;
        o.grid_width = 96;
        o.grid_height = 72;
        o.light_pass = penumbra::AfhLightPass::Compute;
        o.compute_triangles = 64;  // several chunks
        penumbra::AliasFreeHardShadows pipeline(o);
        pipeline.reserve(w.samples());
        pipeline.validateCasters(casters.data(), ranges);
        const auto frame = [&] {
            return depth ? pipeline.run(w.depthInput(), w.light, casters.data(), ranges)
                         : pipeline.run(w.bufferInput(), w.samples(), w.light, casters.data(), ranges);
        };
        checkContract(record(frame), std::string("run, compute light pass, ") + (depth ? "depth" : "buffer") + " input");
        GlAudit audit;
        audit.start();
        CHECK(frame() == Status::Ok);
        audit.stop();
        for (const std::string& name : audit.graphicsCalls()) MESSAGE("graphics-pipeline call in a compute frame: ", name);
        CHECK(!audit.overflowed());
        CHECK(audit.graphicsCalls().empty());
        CHECK(pipeline.readFrame().chunks > 1);
        queueEngineError();
        frame();
        CHECK(glGetError() == GL_INVALID_ENUM);
    }
}

TEST_CASE("LightLutGenerator::generate: seed and certified, one and several dispatches") {
    context();
    const std::vector<glm::dvec3> samples = penumbra::reference::sphereLightSamples(glm::dvec3(0.0), 0.999, 160, 3);
    for (const bool certified : {false, true}) {
        penumbra::LightLutOptions options;
        options.resolution = 16;
        options.certified = certified;
        const penumbra::LightLutSetup setup = penumbra::lightLutSetup(samples, 160, options);
        penumbra::gl::Buffer table(setup.tableBytes());
        for (const uint64_t window : {uint64_t(0), uint64_t(16u * 16u * 16u * 5u)}) {  // driver limits; slabs of 5
            penumbra::LightLutGeneratorOptions limits;
            limits.max_binding_bytes = window;
            penumbra::LightLutGenerator generator(penumbra::ShaderLibrary::embedded(), {}, limits);
            generator.reserve(setup);
            generator.validate(setup, range(table));
            const std::string name = std::string("LightLutGenerator::generate, ") + (certified ? "certified" : "seed") +
                                     ", " + std::to_string(generator.dispatches().size()) + " dispatch(es)";
            checkContract(record([&] { return generator.generate(setup, range(table)); }), name);
            queueEngineError();
            generator.generate(setup, range(table));
            CHECK(glGetError() == GL_INVALID_ENUM);
            const Recorded misuse = record([&] { return generator.generate(setup, {table.id(), 0, 16}); });
            CHECK(misuse.status == Status::RangeTooSmall);
            CHECK(misuse.calls == 0);
            CHECK(misuse.allocations == 0);
        }
    }
}

TEST_CASE("DeepShadowMapBuilder::build: grey and per-triangle opacity, a medium, the whole mip chain") {
    context();
    World w;
    const auto [positions, indices] = penumbra::test::castersWithoutGround(w.scene);
    penumbra::DsmOptions o;
    o.resolution = 32;
    o.samples = 4;
    o.levels = 0;
    const penumbra::DsmSetup setup = penumbra::deepShadowMapSetup(o);
    penumbra::gl::DeepShadowMapBuilder builder(setup);
    auto position_buffer = penumbra::gl::Buffer::fromVector(positions);
    auto index_buffer = penumbra::gl::Buffer::fromVector(indices);
    std::vector<glm::vec4> per_triangle(indices.size() / 3, glm::vec4(0.4f, 0.5f, 0.6f, 0.0f));
    auto triangle_buffer = penumbra::gl::Buffer::fromVector(per_triangle);
    penumbra::gl::DsmCasterBuffers casters;
    casters.positions = range(position_buffer);
    casters.indices = range(index_buffer);
    casters.index_count = static_cast<uint32_t>(indices.size());
    penumbra::DsmLight light;
    light.view = glm::lookAt(w.scene.light.position, glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, 1.0f));
    light.projection = glm::perspective(glm::radians(70.0f), 1.0f, 0.5f, 20.0f);
    penumbra::DsmOpacity grey;
    grey.mesh = glm::vec3(0.5f);
    checkContract(record([&] {
                      builder.build(light, grey, casters);
                      return Status::Ok;
                  }),
                  "DeepShadowMapBuilder::build, grey opacity, 32^2, S = 4, mips");
    penumbra::gl::DsmCasterBuffers coloured = casters;
    coloured.triangle_opacity = range(triangle_buffer);
    penumbra::DsmMedium medium;
    medium.lo = glm::vec3(-1.0f);
    medium.hi = glm::vec3(1.0f);
    medium.sigma_t = 0.5f;
    penumbra::checkDsmMedium(medium);
    checkContract(record([&] {
                      builder.build(light, grey, coloured, medium);
                      return Status::Ok;
                  }),
                  "DeepShadowMapBuilder::build, per-triangle opacity, medium");
    queueEngineError();
    builder.build(light, grey, casters);
    CHECK(glGetError() == GL_INVALID_ENUM);
}

TEST_CASE("ShadowEdgeStencil: run (provable and Chebyshev), writeSampleBuffer and resolve") {
    context();
    World w;
    penumbra::AliasFreeHardOptions options;
    options.grid_width = 96;
    options.grid_height = 72;
    penumbra::AaPatternOptions pattern;
    pattern.samples = 4;
    const penumbra::gl::AaCasterBuffers casters = w.aaCasters();
    const penumbra::BufferRange centres = range(w.gbuffer.positionBuffer()), normals = range(w.gbuffer.faceBuffer());
    for (const auto kind : {penumbra::gl::AaStencilKind::Provable, penumbra::gl::AaStencilKind::Chebyshev}) {
        penumbra::gl::ShadowEdgeStencil stencil(96, 72, options, pattern, {}, 1u << 20, penumbra::ShaderLibrary::embedded(),
                                                kind);
        const std::string name = kind == penumbra::gl::AaStencilKind::Provable ? "provable" : "Chebyshev";
        checkContract(record([&] { return stencil.run(centres, normals, w.view, w.light, casters); }),
                      "ShadowEdgeStencil::run, " + name);
        penumbra::gl::Buffer positions(stencil.sampleBufferBytes()), sample_normals(stencil.sampleBufferBytes());
        penumbra::gl::Buffer states(4ull * stencil.sampleCount(penumbra::AaMode::Full)), visible(4ull * w.samples());
        for (const auto mode : {penumbra::AaMode::Edge, penumbra::AaMode::Full}) {
            const std::string m = mode == penumbra::AaMode::Edge ? "edge" : "full";
            checkContract(record([&] { return stencil.writeSampleBuffer(mode, range(positions), range(sample_normals), 512); }),
                          "ShadowEdgeStencil::writeSampleBuffer, " + name + ", " + m);
            checkContract(record([&] { return stencil.resolve(mode, range(states), range(visible), 512); }),
                          "ShadowEdgeStencil::resolve, " + name + ", " + m);
        }
        queueEngineError();
        stencil.run(centres, normals, w.view, w.light, casters);
        CHECK(glGetError() == GL_INVALID_ENUM);
    }
}
