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
#include "support/light_volume_maps.hpp"

#include <penumbra/gl/deep_shadow_map.hpp>
#include <penumbra/gl/light_lut.hpp>
#include <penumbra/gl/light_volume.hpp>
#include <penumbra/gl/pipelines/alias_free_hard.hpp>
#include <penumbra/gl/pipelines/sample_based_soft.hpp>
#include <penumbra/gl/shadow_edge_stencil.hpp>
#include <penumbra/gl/state.hpp>
#include <penumbra/light_samples.hpp>
#include <penumbra/reference/light_samples.hpp>
#include <penumbra/scene/gl_scene.hpp>
#include <penumbra/scene/scene.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <functional>
#include <optional>
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

// ---------------------------------------------------------------------------------------------
// Buffer bindings (issue 41 item 8). README's contract: "get your state back untouched except for
// what each header lists". Headers list indexed SSBO / UBO points and, for a few per-frame calls,
// the draw- or dispatch-indirect binding; no setup call, destructor or frame may change the
// engine's *generic* buffer bindings or indexed points it does not list. Two ways blocks broke
// that: glBindBufferBase / glBindBufferRange also set the generic binding of their target, and
// deleting a buffer bound at an indexed point resets the generic binding on Mesa (bufferobj.c
// unbinds through its bind_buffer_base_* helpers, which set the generic one to 0).
namespace {

/// The engine's buffers at every generic target a block could disturb and at the top four indexed
/// SSBO and UBO points (no block's default bindings come near them). Pixel pack / unpack and query
/// buffers stay unbound: they redirect uploads and read-backs, a different contract.
class EngineBindings {
public:
    struct Generic {
        GLenum target, binding;
        const char* name;
    };
    static constexpr Generic kGeneric[] = {
        {GL_SHADER_STORAGE_BUFFER, GL_SHADER_STORAGE_BUFFER_BINDING, "GL_SHADER_STORAGE_BUFFER"},
        {GL_UNIFORM_BUFFER, GL_UNIFORM_BUFFER_BINDING, "GL_UNIFORM_BUFFER"},
        {GL_DISPATCH_INDIRECT_BUFFER, GL_DISPATCH_INDIRECT_BUFFER_BINDING, "GL_DISPATCH_INDIRECT_BUFFER"},
        {GL_DRAW_INDIRECT_BUFFER, GL_DRAW_INDIRECT_BUFFER_BINDING, "GL_DRAW_INDIRECT_BUFFER"},
        {GL_COPY_READ_BUFFER, GL_COPY_READ_BUFFER_BINDING, "GL_COPY_READ_BUFFER"},
        {GL_COPY_WRITE_BUFFER, GL_COPY_WRITE_BUFFER_BINDING, "GL_COPY_WRITE_BUFFER"},
        {GL_ATOMIC_COUNTER_BUFFER, GL_ATOMIC_COUNTER_BUFFER_BINDING, "GL_ATOMIC_COUNTER_BUFFER"},
        {GL_TRANSFORM_FEEDBACK_BUFFER, GL_TRANSFORM_FEEDBACK_BUFFER_BINDING, "GL_TRANSFORM_FEEDBACK_BUFFER"},
        {GL_TEXTURE_BUFFER, GL_TEXTURE_BUFFER_BINDING, "GL_TEXTURE_BUFFER"},
        {GL_ARRAY_BUFFER, GL_ARRAY_BUFFER_BINDING, "GL_ARRAY_BUFFER"}};
    static constexpr size_t kGenerics = sizeof kGeneric / sizeof kGeneric[0];
    static constexpr GLuint kIndexed = 4;
    static constexpr GLsizeiptr kIndexedBytes = 64;

    EngineBindings() {
        for (auto& b : buffers_) b = penumbra::gl::Buffer(256);
        const GLint ssbo = penumbra::gl::getInteger(GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS);
        const GLint ubo = penumbra::gl::getInteger(GL_MAX_UNIFORM_BUFFER_BINDINGS);
        REQUIRE(ssbo >= 24);  // above every block's default binding (at most 16)
        REQUIRE(ubo >= 24);
        first_ssbo_ = static_cast<GLuint>(ssbo) - kIndexed;
        first_ubo_ = static_cast<GLuint>(ubo) - kIndexed;
    }

    /// Binds the engine's buffers: indexed points first (glBindBufferRange sets the generic
    /// binding too), then every generic target to a buffer of its own.
    void bind() const {
        for (GLuint i = 0; i < kIndexed; ++i) {
            glBindBufferRange(GL_SHADER_STORAGE_BUFFER, first_ssbo_ + i, indexedSsbo(i), 0, kIndexedBytes);
            glBindBufferRange(GL_UNIFORM_BUFFER, first_ubo_ + i, indexedUbo(i), 0, kIndexedBytes);
        }
        for (size_t t = 0; t < kGenerics; ++t) glBindBuffer(kGeneric[t].target, buffers_[t].id());
    }

    /// Number of the engine's bindings that changed, except the generic targets in `listed`
    /// (what the call's header says it changes); each change is reported by name.
    int changed(const std::string& when, std::initializer_list<GLenum> listed) const {
        int changes = 0;
        for (size_t t = 0; t < kGenerics; ++t) {
            if (std::find(listed.begin(), listed.end(), kGeneric[t].target) != listed.end()) continue;
            const GLint now = penumbra::gl::getInteger(kGeneric[t].binding);
            if (now != static_cast<GLint>(buffers_[t].id())) {
                ++changes;
                MESSAGE(when, ": generic ", std::string(kGeneric[t].name), " binding changed from the engine's buffer ",
                        buffers_[t].id(), " to ", now);
            }
        }
        const struct {
            GLenum binding, start, size;
            GLuint first;
            const char* name;
            bool ubo;
        } targets[2] = {{GL_SHADER_STORAGE_BUFFER_BINDING, GL_SHADER_STORAGE_BUFFER_START, GL_SHADER_STORAGE_BUFFER_SIZE,
                         first_ssbo_, "GL_SHADER_STORAGE_BUFFER", false},
                        {GL_UNIFORM_BUFFER_BINDING, GL_UNIFORM_BUFFER_START, GL_UNIFORM_BUFFER_SIZE, first_ubo_,
                         "GL_UNIFORM_BUFFER", true}};
        for (const auto& target : targets) {
            for (GLuint i = 0; i < kIndexed; ++i) {
                const GLuint point = target.first + i;
                const GLuint want = target.ubo ? indexedUbo(i) : indexedSsbo(i);
                GLint buffer = 0;
                GLint64 start = -1, size = -1;
                glGetIntegeri_v(target.binding, point, &buffer);
                glGetInteger64i_v(target.start, point, &start);
                glGetInteger64i_v(target.size, point, &size);
                if (buffer != static_cast<GLint>(want) || start != 0 || size != kIndexedBytes) {
                    ++changes;
                    MESSAGE(when, ": indexed ", std::string(target.name), " binding ", point, " changed from the engine's buffer ",
                            want, " [0, +", kIndexedBytes, ") to ", buffer, " [", start, ", +", size, ")");
                }
            }
        }
        return changes;
    }

    /// Binds the engine's buffers, runs `call`, requires them unchanged but for `listed`.
    template <class Call>
    void around(const std::string& what, std::initializer_list<GLenum> listed, Call&& call) const {
        bind();
        call();
        CHECK_MESSAGE(changed(what, listed) == 0, what, " changed the engine's buffer bindings");
    }

private:
    std::array<penumbra::gl::Buffer, kGenerics + 2 * kIndexed> buffers_;
    GLuint first_ssbo_ = 0, first_ubo_ = 0;

    GLuint indexedSsbo(GLuint i) const { return buffers_[kGenerics + i].id(); }
    GLuint indexedUbo(GLuint i) const { return buffers_[kGenerics + kIndexed + i].id(); }
};

}  // namespace

TEST_CASE("EngineBindings: the check sees a generic and an indexed binding change (it can fail)") {
    context();
    const EngineBindings engine;
    const penumbra::gl::Buffer other(256);
    engine.bind();
    CHECK(engine.changed("nothing", {}) == 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, other.id());  // sets the generic binding too
    CHECK(engine.changed("glBindBufferBase(SSBO, 0)", {}) == 1);
    CHECK(engine.changed("glBindBufferBase(SSBO, 0), generic SSBO listed", {GL_SHADER_STORAGE_BUFFER}) == 0);
    engine.bind();
    const GLuint top = static_cast<GLuint>(penumbra::gl::getInteger(GL_MAX_UNIFORM_BUFFER_BINDINGS)) - 1;
    const GLuint other_id = other.id();
    glBindBuffersBase(GL_UNIFORM_BUFFER, top, 1, &other_id);
    CHECK(engine.changed("glBindBuffersBase(UBO, top)", {}) == 1);
    engine.bind();
    {
        // Mesa resets the generic binding when a buffer bound at an indexed point is deleted.
        const penumbra::gl::Buffer temporary(256);
        const GLuint id = temporary.id();
        glBindBuffersBase(GL_SHADER_STORAGE_BUFFER, 0, 1, &id);
    }
    CHECK(engine.changed("deleting a buffer bound at indexed SSBO 0", {}) == 0);
}

TEST_CASE("Scanner: construction, reserve growth, scans and destruction keep the engine's buffer bindings") {
    context();
    const EngineBindings engine;
    for (const bool subgroups : {true, false}) {
        CAPTURE(subgroups);
        penumbra::ScanOptions options;
        options.allow_subgroups = subgroups;
        std::optional<penumbra::Scanner> scanner;
        engine.around("Scanner construction", {}, [&] { scanner.emplace(options); });
        MESSAGE("subgroup mode ", static_cast<int>(scanner->subgroupMode()));
        const uint64_t small = 1000, large = (1u << 20) + 3;
        std::vector<uint32_t> values(large);
        for (size_t i = 0; i < values.size(); ++i) values[i] = static_cast<uint32_t>(i % 7);
        const penumbra::gl::Buffer in = penumbra::gl::Buffer::fromVector(values);
        const penumbra::gl::Buffer out(large * 4);
        engine.around("Scanner::reserve(1000)", {}, [&] { scanner->reserve(small); });
        engine.around("Scanner::exclusive(1000)", {},
                      [&] { REQUIRE(scanner->exclusive(whole(in), whole(out), small) == Status::Ok); });
        engine.around("Scanner::reserve(2^20 + 3) (growth)", {}, [&] { scanner->reserve(large); });
        engine.around("Scanner::exclusive(2^20 + 3)", {},
                      [&] { REQUIRE(scanner->exclusive(whole(in), whole(out), large) == Status::Ok); });
        engine.around("Scanner destruction", {}, [&] { scanner.reset(); });
        // The scans computed something: the last element's prefix.
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        uint64_t sum = 0;
        for (uint64_t i = 0; i + 1 < large; ++i) sum += values[i];
        CHECK(out.download<uint32_t>((large - 1) * 4, 1)[0] == static_cast<uint32_t>(sum));
    }
}

TEST_CASE("LightLutGenerator: setup, generate and destruction keep the engine's buffer bindings") {
    context();
    const EngineBindings engine;
    const std::vector<glm::dvec3> samples = penumbra::reference::sphereLightSamples(glm::dvec3(0.0), 0.999, 160, 3);
    for (const bool certified : {false, true}) {
        CAPTURE(certified);
        penumbra::LightLutOptions options;
        options.resolution = 16;
        options.certified = certified;
        const penumbra::LightLutSetup setup = penumbra::lightLutSetup(samples, 160, options);
        const penumbra::gl::Buffer table(setup.tableBytes());
        std::optional<penumbra::LightLutGenerator> generator;
        engine.around("LightLutGenerator construction", {}, [&] { generator.emplace(); });
        engine.around("LightLutGenerator::reserve", {}, [&] { generator->reserve(setup); });
        engine.around("LightLutGenerator::validate", {}, [&] { generator->validate(setup, whole(table)); });
        engine.around("LightLutGenerator::generate", {},
                      [&] { REQUIRE(generator->generate(setup, whole(table)) == Status::Ok); });
        engine.around("LightLutGenerator destruction", {}, [&] { generator.reset(); });
    }
}

TEST_CASE("AliasFreeHardShadows: setup, frames and destruction keep the engine's buffer bindings") {
    context();
    const EngineBindings engine;
    World w(penumbra::scene::builtin("torus_knot"));
    auto draw = [&](penumbra::CasterClass cls) { w.drawClass(cls); };
    for (int config = 0; config < 2; ++config) {
        CAPTURE(config);
        penumbra::AliasFreeHardOptions o;
        o.grid_width = 96;
        o.grid_height = 72;
        if (config == 1) o.variant = penumbra::ConservativeVariant::Exact;
        std::optional<penumbra::AliasFreeHardShadows> pipeline;
        engine.around("AliasFreeHardShadows construction", {}, [&] { pipeline.emplace(o); });
        engine.around("AliasFreeHardShadows::reserve", {}, [&] { pipeline->reserve(w.samples() / 2); });
        engine.around("AliasFreeHardShadows::reserve (growth)", {}, [&] { pipeline->reserve(w.samples()); });
        // Listed: the two-pass emitter's spill buffer goes to GL_DRAW_INDIRECT_BUFFER.
        engine.around("AliasFreeHardShadows::run (buffer input)", {GL_DRAW_INDIRECT_BUFFER}, [&] {
            REQUIRE(pipeline->run(w.bufferInput(), w.samples(), w.light, draw) == Status::Ok);
        });
        engine.around("AliasFreeHardShadows::run (depth input)", {GL_DRAW_INDIRECT_BUFFER},
                      [&] { REQUIRE(pipeline->run(w.depthInput(), w.light, draw) == Status::Ok); });
        engine.around("AliasFreeHardShadows destruction", {}, [&] { pipeline.reset(); });
    }
}

TEST_CASE("SampleBasedSoftShadows: setup, frames and destruction keep the engine's buffer bindings") {
    context();
    const EngineBindings engine;
    World w(penumbra::scene::columns(4));
    const penumbra::test::GlSoftLight soft(w, 32);
    const penumbra::BufferRange lut_table = soft.table();
    penumbra::SampleBasedSoftGpuOptions options;
    options.grid_width = options.grid_height = 64;
    options.max_list_blocks = 256;
    std::optional<penumbra::SampleBasedSoftShadows> pipeline;
    engine.around("SampleBasedSoftShadows construction", {}, [&] {
        pipeline.emplace(options, soft.sets, &soft.lut, soft.influence, w.light.view_projection);
    });
    engine.around("SampleBasedSoftShadows::reserve", {}, [&] { pipeline->reserve(w.samples()); });
    const penumbra::SampleDepthInput input{w.gbuffer.depthTexture(), 0, w.view};
    engine.around("SampleBasedSoftShadows::validate", {}, [&] { pipeline->validate(input, lut_table); });
    const auto draw = [&](penumbra::CasterClass c) { w.gpu.drawClass(c == penumbra::CasterClass::Closed); };
    // Listed: the deferral buffer goes to GL_DISPATCH_INDIRECT_BUFFER.
    engine.around("SampleBasedSoftShadows::run", {GL_DISPATCH_INDIRECT_BUFFER},
                  [&] { REQUIRE(pipeline->run(input, lut_table, draw) == Status::Ok); });
    engine.around("SampleBasedSoftShadows destruction", {}, [&] { pipeline.reset(); });
}

TEST_CASE("DeepShadowMapBuilder: construction, build and destruction keep the engine's buffer bindings") {
    context();
    const EngineBindings engine;
    const penumbra::scene::Scene scene = penumbra::scene::hairball(200, 3, false);
    const auto [positions, indices] = penumbra::test::castersWithoutGround(scene);
    penumbra::DsmLight light;
    light.view = glm::lookAt(glm::vec3(0.5f, 6.0f, 1.0f), glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, 1.0f));
    light.projection = glm::perspective(glm::radians(60.0f), 1.0f, 1.0f, 12.0f);
    penumbra::DsmOptions o;
    o.resolution = 32;
    o.samples = 4;
    o.levels = 0;
    const penumbra::DsmSetup setup = penumbra::deepShadowMapSetup(o);
    const penumbra::gl::Buffer position_buffer = penumbra::gl::Buffer::fromVector(positions);
    const penumbra::gl::Buffer index_buffer = penumbra::gl::Buffer::fromVector(indices);
    penumbra::gl::DsmCasterBuffers casters;
    casters.positions = whole(position_buffer);
    casters.indices = whole(index_buffer);
    casters.index_count = static_cast<uint32_t>(indices.size());
    penumbra::DsmOpacity opacity;
    opacity.mesh = glm::vec3(0.5f);
    std::optional<penumbra::gl::DeepShadowMapBuilder> builder;
    engine.around("DeepShadowMapBuilder construction", {}, [&] { builder.emplace(setup); });
    engine.around("DeepShadowMapBuilder::build", {}, [&] { builder->build(light, opacity, casters); });
    engine.around("DeepShadowMapBuilder destruction", {}, [&] { builder.reset(); });
}

TEST_CASE("ShadowEdgeStencil: construction, run and destruction keep the engine's buffer bindings") {
    context();
    const EngineBindings engine;
    World w(penumbra::scene::columns(4));
    penumbra::AliasFreeHardOptions options;
    options.grid_width = 96;
    options.grid_height = 72;
    penumbra::AaPatternOptions pattern;
    pattern.samples = 4;
    const penumbra::gl::AaCasterBuffers casters = w.aaCasters();
    std::optional<penumbra::gl::ShadowEdgeStencil> stencil;
    engine.around("ShadowEdgeStencil construction", {}, [&] {
        stencil.emplace(96, 72, options, pattern, penumbra::ProvableStencilOptions{}, 1u << 22,
                        penumbra::ShaderLibrary::embedded(), penumbra::gl::AaStencilKind::Chebyshev);
    });
    engine.around("ShadowEdgeStencil::run", {}, [&] {
        REQUIRE(stencil->run(whole(w.gbuffer.positionBuffer()), whole(w.gbuffer.faceBuffer()), w.view, w.light,
                             casters) == Status::Ok);
    });
    engine.around("ShadowEdgeStencil destruction", {}, [&] { stencil.reset(); });
}

TEST_CASE("LightVolumeTessellator: construction, tessellate and destruction keep the engine's buffer bindings") {
    context();
    const EngineBindings engine;
    const uint32_t r = 64;
    std::vector<float> depth(r * r);
    for (size_t t = 0; t < depth.size(); ++t) depth[t] = (t % 7 == 0) ? 0.3f : 0.8f;
    penumbra::gl::Texture texture(GL_TEXTURE_2D);
    glTextureStorage2D(texture.id(), 1, GL_DEPTH_COMPONENT32F, GLsizei(r), GLsizei(r));
    glTextureSubImage2D(texture.id(), 0, 0, 0, GLsizei(r), GLsizei(r), GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
    std::optional<penumbra::gl::LightVolumeTessellator> tessellator;
    engine.around("LightVolumeTessellator construction", {},
                  [&] { tessellator.emplace(penumbra::test::volumeSetup(r, 1e-6)); });
    engine.around("LightVolumeTessellator::tessellate", {}, [&] { tessellator->tessellate(texture.id()); });
    engine.around("LightVolumeTessellator destruction", {}, [&] { tessellator.reset(); });
}
