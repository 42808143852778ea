// The engine's leftover GL state must not change what a block computes. An engine calls a block
// in the middle of its frame: its scissor box from a UI pass, wireframe polygon mode from a debug
// toggle, user clip planes, D3D-style clip control (upper-left origin, depth 0..1), primitive
// restart, colour masks, a narrowed depth range. Every block that rasterizes (the hard and soft
// pipelines' predicate and light passes, the deep shadow map's build, the shadow-edge stencil,
// the light volume) sets the rasterizer state it relies on (penumbra::gl::setPassRasterState,
// listed in each header's GL state contract). Each case runs a block once in GL's default state
// and once under that hostile state, and requires the same results bit for bit. Holds on any
// driver: both runs are the same driver's.
#include "support/engine_state.hpp"
#include "support/gl_test_support.hpp"
#include "support/gl_world.hpp"

#include <penumbra/gl/deep_shadow_map.hpp>
#include <penumbra/gl/light_volume.hpp>
#include <penumbra/gl/pipelines/alias_free_hard.hpp>
#include <penumbra/gl/pipelines/sample_based_soft.hpp>
#include <penumbra/gl/shadow_edge_stencil.hpp>
#include <penumbra/gl/state.hpp>
#include <penumbra/light_samples.hpp>
#include <penumbra/scene/gl_scene.hpp>
#include <penumbra/scene/scene.hpp>

#include <doctest/doctest.h>

#include <cstring>
#include <functional>
#include <string>
#include <vector>

namespace {

using penumbra::Status;
using penumbra::test::context;
using penumbra::test::setDefaultState;
using penumbra::test::setHostileState;

penumbra::BufferRange whole(const penumbra::gl::Buffer& b) { return {b.id(), 0, b.size()}; }

/// Runs `frame` (which returns its results as bytes) in the default state, then under the hostile
/// state; both results must be equal and `frame` must have produced something.
void checkUnchanged(const std::string& what, const std::function<std::vector<uint32_t>()>& frame) {
    INFO(what);
    setDefaultState();
    const std::vector<uint32_t> reference = frame();
    setHostileState();
    const std::vector<uint32_t> hostile = frame();
    setDefaultState();
    REQUIRE(reference.size() == hostile.size());
    size_t differing = 0, nonzero = 0;
    for (size_t i = 0; i < reference.size(); ++i) {
        differing += reference[i] != hostile[i];
        nonzero += reference[i] != 0u;
    }
    MESSAGE(what, ": ", differing, " of ", reference.size(), " result words differ under the engine's state");
    CHECK(nonzero > 0);
    CHECK(differing == 0);
}

template <typename T>
std::vector<uint32_t> asWords(const std::vector<T>& values) {
    std::vector<uint32_t> words((values.size() * sizeof(T) + 3) / 4);
    if (!values.empty()) std::memcpy(words.data(), values.data(), values.size() * sizeof(T));
    return words;
}

using World = penumbra::test::GlWorld;

}  // namespace

TEST_CASE("AliasFreeHardShadows: the engine's raster state changes no state (buffer and depth input)") {
    context();
    World w(penumbra::scene::builtin("torus_knot"));
    auto draw = [&](penumbra::CasterClass cls) { w.drawClass(cls); };
    for (int config = 0; config < 2; ++config) {
        penumbra::AliasFreeHardOptions o;
        o.grid_width = 96;
        o.grid_height = 72;
        if (config == 1) o.variant = penumbra::ConservativeVariant::Exact;
        penumbra::AliasFreeHardShadows pipeline(o);
        pipeline.reserve(w.samples());
        const std::string name = config == 0 ? "hard, fixed6 two-pass" : "hard, exact variant";
        checkUnchanged(name + ", buffer input", [&] {
            REQUIRE(pipeline.run(w.bufferInput(), w.samples(), w.light, draw) == Status::Ok);
            std::vector<uint32_t> states = pipeline.stateBuffer().download<uint32_t>(0, w.samples());
            // Nonzero words only where something is shadowed: the check wants shadows to compare.
            size_t shadowed = 0;
            for (uint32_t s : states) shadowed += s == PENUMBRA_AFH_SHADOWED;
            CHECK(shadowed > 0);
            return states;
        });
        checkUnchanged(name + ", depth input", [&] {
            REQUIRE(pipeline.run(w.depthInput(), w.light, draw) == Status::Ok);
            return pipeline.stateBuffer().download<uint32_t>(0, w.samples());
        });
    }
}

TEST_CASE("SampleBasedSoftShadows: the engine's raster state changes no mask (depth input, exact, N = 128)") {
    context();
    World w(penumbra::scene::columns(4));
    const penumbra::test::GlSoftLight soft(w, 32);
    const penumbra::BufferRange lut_table = soft.table();
    penumbra::SampleBasedSoftGpuOptions options;
    options.grid_width = options.grid_height = 64;
    options.max_list_blocks = 256;
    penumbra::SampleBasedSoftShadows pipeline(options, soft.sets, &soft.lut, soft.influence, w.light.view_projection);
    pipeline.reserve(w.samples());
    const penumbra::SampleDepthInput input{w.gbuffer.depthTexture(), 0, w.view};
    pipeline.validate(input, lut_table);
    const auto draw = [&](penumbra::CasterClass c) { w.gpu.drawClass(c == penumbra::CasterClass::Closed); };
    checkUnchanged("soft, depth input", [&] {
        REQUIRE(pipeline.run(input, lut_table, draw) == Status::Ok);
        return pipeline.readMasks();
    });
    // gl::StateSave puts back what the pipeline changes, its stencil state included.
    setHostileState();
    const std::vector<double> before = penumbra::test::rasterStateSnapshot();
    {
        penumbra::gl::StateSave saved;
        REQUIRE(pipeline.run(input, lut_table, draw) == Status::Ok);
        CHECK(penumbra::test::rasterStateSnapshot() != before);
    }
    CHECK(penumbra::test::rasterStateSnapshot() == before);
    setDefaultState();
}

TEST_CASE("DeepShadowMapBuilder::build: the engine's raster state changes no fragment and no vertex") {
    context();
    const penumbra::scene::Scene scene = penumbra::scene::hairball(600, 3, false);
    const auto [positions, indices] = penumbra::test::castersWithoutGround(scene);
    penumbra::scene::Bounds bounds;
    for (const auto& p : positions) bounds.extend(p);
    const glm::vec3 centre = bounds.center();
    const float radius = 0.5f * glm::length(bounds.size());
    const glm::vec3 eye = centre + glm::normalize(glm::vec3(0.3f, 1.0f, 0.2f)) * (3.0f * radius);
    const float dist = glm::length(eye - centre);
    penumbra::DsmLight light;
    light.view = glm::lookAt(eye, centre, glm::vec3(0.0f, 0.0f, 1.0f));
    light.projection = glm::perspective(2.0f * std::asin(radius / dist), 1.0f, dist - 1.1f * radius, dist + 1.1f * radius);
    penumbra::DsmOptions o;
    o.resolution = 32;
    o.samples = 16;
    o.levels = 0;
    const penumbra::DsmSetup setup = penumbra::deepShadowMapSetup(o);
    penumbra::gl::DeepShadowMapBuilder builder(setup);
    const penumbra::gl::Buffer position_buffer = penumbra::gl::Buffer::fromVector(positions);
    const penumbra::gl::Buffer index_buffer = penumbra::gl::Buffer::fromVector(indices);
    penumbra::gl::DsmCasterBuffers casters;
    casters.positions = whole(position_buffer);
    casters.indices = whole(index_buffer);
    casters.index_count = static_cast<uint32_t>(indices.size());
    penumbra::DsmOpacity opacity;
    opacity.mesh = glm::vec3(0.5f);
    checkUnchanged("deep shadow map 32^2, S = 16, mips", [&] {
        builder.build(light, opacity, casters);
        const penumbra::DsmFragmentsCpu fragments = builder.readFragments();
        const penumbra::DsmMapCpu map = builder.readMap();
        std::vector<uint32_t> words = asWords(fragments.offsets);
        for (const auto& f : fragments.fragments) {
            const std::vector<uint32_t> record = asWords(std::vector<penumbra::DsmFragment>{f});
            words.insert(words.end(), record.begin(), record.end());
        }
        for (uint32_t l = 0; l < map.levels; ++l) {
            const std::vector<uint32_t> offsets = map.offsets[l], vertices = asWords(map.vertices[l]);
            words.insert(words.end(), offsets.begin(), offsets.end());
            words.insert(words.end(), vertices.begin(), vertices.end());
        }
        return words;
    });
}

TEST_CASE("ShadowEdgeStencil::run: the engine's raster state changes no flag (provable and Chebyshev)") {
    context();
    World w(penumbra::scene::columns(4));
    penumbra::AliasFreeHardOptions options;
    options.grid_width = 96;
    options.grid_height = 72;
    penumbra::AaPatternOptions pattern;
    pattern.samples = 4;
    const penumbra::gl::AaCasterBuffers casters = w.aaCasters();
    for (const auto kind : {penumbra::gl::AaStencilKind::Provable, penumbra::gl::AaStencilKind::Chebyshev}) {
        penumbra::gl::ShadowEdgeStencil stencil(96, 72, options, pattern, {}, 1u << 22, penumbra::ShaderLibrary::embedded(),
                                                kind);
        checkUnchanged(kind == penumbra::gl::AaStencilKind::Provable ? "provable stencil" : "Chebyshev stencil", [&] {
            REQUIRE(stencil.run(whole(w.gbuffer.positionBuffer()), whole(w.gbuffer.faceBuffer()), w.view, w.light,
                                casters) == Status::Ok);
            std::vector<uint32_t> words = stencil.readStencil();
            const auto status = stencil.readStatus();  // one array: begin() and end() of the same read
            words.insert(words.end(), status.begin(), status.end());
            return words;
        });
    }
}

TEST_CASE("gl::StateSave puts back the engine's state around a block (hard pipeline, deep shadow map)") {
    context();
    World w(penumbra::scene::builtin("torus_knot"));
    auto draw = [&](penumbra::CasterClass cls) { w.drawClass(cls); };
    penumbra::AliasFreeHardOptions o;
    o.grid_width = 96;
    o.grid_height = 72;
    penumbra::AliasFreeHardShadows pipeline(o);
    pipeline.reserve(w.samples());
    setHostileState();
    // Bindings an engine holds too: a program, a vertex array, buffers at the indexed points.
    const penumbra::gl::Buffer engine_buffer(256);
    for (GLuint i = 0; i < 8; ++i) {
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, i, engine_buffer.id(), 0, 64);
        glBindBufferRange(GL_UNIFORM_BUFFER, i, engine_buffer.id(), 0, 64);
    }
    glBlendFuncSeparatei(0, GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ZERO);
    glBlendEquationSeparatei(0, GL_FUNC_SUBTRACT, GL_MAX);
    glEnablei(GL_BLEND, 0);
    glViewport(3, 4, 50, 60);
    const std::vector<double> before = penumbra::test::rasterStateSnapshot();
    {
        penumbra::gl::StateSave saved;
        REQUIRE(pipeline.run(w.depthInput(), w.light, draw) == Status::Ok);
        CHECK(penumbra::test::rasterStateSnapshot() != before);  // the block did change state
    }
    const std::vector<double> after = penumbra::test::rasterStateSnapshot();
    REQUIRE(before.size() == after.size());
    for (size_t i = 0; i < before.size(); ++i) {
        CAPTURE(i);
        CHECK(before[i] == after[i]);
    }
    setDefaultState();
    glDisablei(GL_BLEND, 0);
    glBlendFuncSeparatei(0, GL_ONE, GL_ZERO, GL_ONE, GL_ZERO);
    glBlendEquationSeparatei(0, GL_FUNC_ADD, GL_FUNC_ADD);
}
