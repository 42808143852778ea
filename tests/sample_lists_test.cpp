// View-sample lists (sintorn2008 §3.1, §4.3, Fig. 9): the GPU structure equals the CPU twin's
// (modulo order inside a list), both satisfy the structure's invariants checked here
// independently (every accepted sample exactly once, in the list of the texel a double-precision
// projection puts it in; offsets = running sum of counts), texel borders follow the documented
// rule, rejections are counted by reason, bad input throws, the GLSL walk API visits every
// sample from a fragment shader, the §4.3 fit contains every accepted sample, and the Fig. 9
// statistics agree. Seeds are printed (override with PENUMBRA_SEED); outputs are poisoned first.
#include "shader_catalog.hpp"

#include "support/gl_test_support.hpp"

#include <penumbra/gl/headless.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/sample_lists.hpp>
#include <penumbra/gl/shader.hpp>

#include <glm/gtc/matrix_transform.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace {

using penumbra::LightDepthRange;
using penumbra::SampleListsCpu;
using penumbra::SampleListsLight;
using penumbra::SampleListsOptions;
using penumbra::SampleListsSetup;
using penumbra::SampleRejection;
namespace gl = penumbra::gl;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr uint32_t kPoison = 0xDEADBEEFu;

using penumbra::test::context;
using penumbra::test::testSeed;
using penumbra::Status;

penumbra::SampleListBuilder& builder() {
    static penumbra::SampleListBuilder b;
    return b;
}

penumbra::BufferRange range(const gl::Buffer& b) { return {b.id(), 0, b.size()}; }
penumbra::SampleBufferInput bufferInput(const gl::Buffer& positions, const gl::Buffer& normals) {
    return {range(positions), range(normals)};
}

// Load-time steps (reserve, validate: these throw on bad objects), then the per-frame build.
template <typename Input>
Status buildChecked(const SampleListsSetup& setup, const SampleListsLight& light, const Input& input,
                    const penumbra::SampleListsBuffers& out, const SampleListsOptions& options = {},
                    const penumbra::SampleListsBuild& build = {}) {
    builder().reserve(setup);
    builder().validate(setup, input, out, options);
    return builder().build(setup, light, input, out, options, build);
}

uint32_t code(SampleRejection r) { return penumbra::kSampleListsRejected + static_cast<uint32_t>(r); }

// A point light above the origin looking down, and a directional light from the upper side.
SampleListsLight pointLight() {
    SampleListsLight l;
    const glm::vec3 position(0.3f, 4.0f, 0.2f);
    l.view_projection = glm::perspective(glm::radians(60.0f), 1.0f, 0.5f, 8.0f) *
                        glm::lookAt(position, glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, 1.0f));
    l.light = glm::vec4(position, 1.0f);
    return l;
}

SampleListsLight directionalLight() {
    SampleListsLight l;
    const glm::vec3 towards = glm::normalize(glm::vec3(0.2f, 1.0f, 0.3f));
    l.view_projection = glm::ortho(-2.0f, 2.0f, -2.0f, 2.0f, 0.1f, 10.0f) *
                        glm::lookAt(towards * 5.0f, glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, 1.0f));
    l.light = glm::vec4(towards, 0.0f);
    return l;
}

// GPU buffers of one build, allocated from the setup's sizes.
struct GpuLists {
    gl::Buffer counts, offsets, list_positions, list_ids, sample_slots, sample_texels, header, frustum;
    explicit GpuLists(const SampleListsSetup& s)
        : counts(s.counts_bytes), offsets(s.offsets_bytes), list_positions(s.list_positions_bytes),
          list_ids(s.list_ids_bytes), sample_slots(s.sample_slots_bytes), sample_texels(s.sample_texels_bytes),
          header(s.header_bytes), frustum(sizeof(penumbra::SampleListsFrustum)) {}
    penumbra::SampleListsBuffers ids() const {
        return {range(counts),       range(offsets),       range(list_positions), range(list_ids),
                range(sample_slots), range(sample_texels), range(header),         range(frustum)};
    }
    void poison() {
        for (gl::Buffer* b :
             {&counts, &offsets, &list_positions, &list_ids, &sample_slots, &sample_texels, &header, &frustum}) {
            b->fill(kPoison);
        }
    }
};

// The GPU's §4.3 fit of a build with fit_frustum (read back: frustum block + header keys).
template <typename Input>
penumbra::LightFrustumFit gpuFit(const SampleListsSetup& setup, const SampleListsLight& light, const Input& input,
                                 const GpuLists& lists, const SampleListsOptions& options = {}) {
    penumbra::SampleListsBuild build;
    build.fit_frustum = true;
    REQUIRE(buildChecked(setup, light, input, lists.ids(), options, build) == Status::Ok);
    penumbra::LightFrustumFit fit =
        penumbra::lightFrustumFitFromFrustum(penumbra::SampleListBuilder::readFrustum(lists.ids().frustum));
    fit.keys = penumbra::SampleListBuilder::readHeader(lists.ids().header);
    return fit;
}

penumbra::SampleListStatistics gpuStatistics(const SampleListsSetup& setup, const GpuLists& lists) {
    REQUIRE(builder().statistics(setup, lists.ids()) == Status::Ok);
    return penumbra::SampleListBuilder::readStatistics(setup, lists.ids());
}

struct Samples {
    std::vector<glm::vec4> positions, normals;
};

// Random samples around the light frustum plus a sprinkling of special values.
Samples randomSamples(std::mt19937& rng, size_t n) {
    std::uniform_real_distribution<float> x(-3.0f, 3.0f), y(-0.5f, 2.5f), unit(-1.0f, 1.0f), pick(0.0f, 1.0f);
    Samples s;
    s.positions.resize(n);
    s.normals.resize(n);
    for (size_t i = 0; i < n; ++i) {
        glm::vec4 p(x(rng), y(rng), x(rng), 1.0f);
        glm::vec3 nrm(unit(rng), unit(rng), unit(rng));
        if (glm::length(nrm) < 1e-3f) nrm = glm::vec3(0.0f, 1.0f, 0.0f);
        glm::vec4 normal(glm::normalize(nrm), 0.0f);
        const float r = pick(rng);
        if (r < 0.02f) p.x = kNaN;
        else if (r < 0.03f) p.y = (r < 0.025f) ? kInf : -kInf;
        else if (r < 0.05f) p.w = 0.0f;
        else if (r < 0.06f) normal.z = kNaN;
        else if (r < 0.07f) p = glm::vec4(1e30f, -1e30f, 1e30f, 1.0f);  // projects to Inf
        else if (r < 0.08f) p.y = -10.0f;  // beyond the point light's far plane
        s.positions[i] = p;
        s.normals[i] = normal;
    }
    return s;
}

// ----- independent checks (not the library's code) ---------------------------------------------

// Double-precision projection of a sample; nullopt when the sample is within a tolerance of a
// decision boundary (texel border, frustum plane, light-facing plane) where float rounding decides.
std::optional<uint32_t> oracleCode(const SampleListsSetup& setup, const SampleListsLight& light,
                                   const SampleListsOptions& options, const glm::vec4& p, const glm::vec4& n) {
    if (p.w == 0.0f) return code(SampleRejection::Background);
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return code(SampleRejection::NonFinite);
    if (options.cull_back_facing && (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z))) {
        return code(SampleRejection::NonFinite);
    }
    const glm::dmat4 t_matrix(penumbra::lightTextureMatrix(light.view_projection, options.depth_range));
    const glm::dvec4 t = t_matrix * glm::dvec4(p.x, p.y, p.z, 1.0);
    if (!std::isfinite(t.x) || !std::isfinite(t.y) || !std::isfinite(t.z) || !std::isfinite(t.w) ||
        std::abs(t.x) > 1e30 || std::abs(t.w) > 1e30) {
        return code(SampleRejection::Outside);
    }
    const double tol = 1e-4 * (std::abs(t.w) + 1e-3);
    auto near = [&](double a, double b) { return std::abs(a - b) < tol; };
    if (near(t.w, 0) || near(t.x, 0) || near(t.x, t.w) || near(t.y, 0) || near(t.y, t.w)) return std::nullopt;
    if (!(t.w > 0) || t.x < 0 || t.x > t.w || t.y < 0 || t.y > t.w) return code(SampleRejection::Outside);
    if (options.depth_range != LightDepthRange::Unclipped) {
        if (near(t.z, 0) || near(t.z, t.w)) return std::nullopt;
        if (t.z < 0 || t.z > t.w) return code(SampleRejection::Depth);
    }
    if (options.cull_back_facing) {
        const glm::dvec3 to_light = light.light.w == 0.0f ? glm::dvec3(light.light)
                                                          : glm::dvec3(light.light) - glm::dvec3(p);
        const double facing = glm::dot(glm::dvec3(n), to_light);
        if (std::abs(facing) < 1e-5 * glm::length(to_light)) return std::nullopt;
        if (facing <= 0) return code(SampleRejection::BackFacing);
    }
    const double gx = t.x / t.w * setup.grid_width, gy = t.y / t.w * setup.grid_height;
    if (std::abs(gx - std::round(gx)) < 1e-3 || std::abs(gy - std::round(gy)) < 1e-3) return std::nullopt;
    const uint32_t x = std::min<uint32_t>(static_cast<uint32_t>(gx), setup.grid_width - 1);
    const uint32_t y = std::min<uint32_t>(static_cast<uint32_t>(gy), setup.grid_height - 1);
    return y * setup.grid_width + x;
}

// Invariants of a structure, checked element by element. `positions` = the input positions by id
// (null for depth input: positions are then only checked for w = 1). Returns the number of
// samples the double-precision oracle could decide (so callers can assert the check had teeth).
size_t checkStructure(const SampleListsSetup& setup, const SampleListsCpu& s, const glm::vec4* positions,
                      const std::vector<std::optional<uint32_t>>* oracle) {
    const uint32_t n = setup.sample_count;
    REQUIRE(s.counts.size() == setup.lists);
    REQUIRE(s.offsets.size() == setup.lists);
    REQUIRE(s.sample_slots.size() == n);
    REQUIRE(s.sample_texels.size() == n);
    // Offsets are the exclusive running sum of the counts.
    uint64_t running = 0;
    size_t bad_offsets = 0;
    for (uint32_t i = 0; i < setup.lists; ++i) {
        bad_offsets += s.offsets[i] != running;
        running += s.counts[i];
    }
    CHECK(bad_offsets == 0);
    CHECK(running == s.header.accepted);
    REQUIRE(s.list_ids.size() >= s.header.accepted);
    REQUIRE(s.list_positions.size() >= s.header.accepted);
    // Walk every list: each entry names a sample of this texel whose slot points back here.
    std::vector<uint32_t> seen(n, 0);
    size_t bad_entries = 0;
    for (uint32_t list = 0; list < setup.lists; ++list) {
        for (uint32_t k = 0; k < s.counts[list]; ++k) {
            const uint32_t slot = s.offsets[list] + k;
            const uint32_t id = s.list_ids[slot];
            if (id >= n) {
                ++bad_entries;
                continue;
            }
            ++seen[id];
            bool ok = s.sample_texels[id] == list && s.sample_slots[id] == slot && s.list_positions[slot].w == 1.0f;
            if (positions) {
                ok = ok && std::memcmp(&s.list_positions[slot], &positions[id], 12) == 0;
            }
            bad_entries += !ok;
        }
    }
    CHECK(bad_entries == 0);
    // Every accepted sample exactly once, every rejected one nowhere, reasons counted.
    size_t bad_samples = 0, decided = 0, oracle_mismatch = 0;
    std::array<uint32_t, 8> reasons{};
    uint32_t accepted = 0;
    for (uint32_t id = 0; id < n; ++id) {
        const uint32_t c = s.sample_texels[id];
        if (c < penumbra::kSampleListsRejected) {
            bad_samples += !(c < setup.lists && seen[id] == 1);
            ++accepted;
        } else {
            bad_samples += !(c - penumbra::kSampleListsRejected < penumbra::kSampleListsReasonCount && seen[id] == 0 &&
                             s.sample_slots[id] == penumbra::kSampleListsNoSlot);
            if (c - penumbra::kSampleListsRejected < 8) ++reasons[c - penumbra::kSampleListsRejected];
        }
        if (oracle && (*oracle)[id]) {
            ++decided;
            oracle_mismatch += *(*oracle)[id] != c;
        }
    }
    CHECK(bad_samples == 0);
    CHECK(oracle_mismatch == 0);
    CHECK(accepted == s.header.accepted);
    for (int r = 0; r < 8; ++r) CHECK(reasons[r] == s.header.rejected[r]);
    return decided;
}

std::vector<std::optional<uint32_t>> oracleCodes(const SampleListsSetup& setup, const SampleListsLight& light,
                                                 const SampleListsOptions& options, const Samples& samples) {
    std::vector<std::optional<uint32_t>> out(samples.positions.size());
    for (size_t i = 0; i < out.size(); ++i) {
        out[i] = oracleCode(setup, light, options, samples.positions[i], samples.normals[i]);
    }
    return out;
}

// GPU build from buffers, poisoned outputs, downloaded.
SampleListsCpu gpuBuild(const SampleListsSetup& setup, const SampleListsLight& light, const Samples& samples,
                        const SampleListsOptions& options, GpuLists* keep = nullptr) {
    auto positions = gl::Buffer::fromVector(samples.positions);
    auto normals = gl::Buffer::fromVector(samples.normals);
    GpuLists lists(setup);
    lists.poison();
    REQUIRE(buildChecked(setup, light, bufferInput(positions, normals), lists.ids(), options) == Status::Ok);
    SampleListsCpu out = penumbra::downloadSampleLists(setup, lists.ids());
    gl::checkErrors("sample lists build");
    if (keep) *keep = std::move(lists);
    return out;
}

SampleListsCpu cpuBuild(const SampleListsSetup& setup, const SampleListsLight& light, const Samples& samples,
                        const SampleListsOptions& options) {
    return penumbra::buildSampleListsCpu(setup, light, samples.positions.data(), samples.normals.data(), options);
}

// Fragment-shader walk of every list (tests/shaders/sample_lists/walk.frag.glsl); checks its
// error counter, the visit count of every sample and every shadow word against the pattern.
void walkLists(const SampleListsSetup& setup, const SampleListsLight& light, const SampleListsOptions& options,
               const GpuLists& lists, const SampleListsCpu& structure, uint32_t bits) {
    CAPTURE(bits);
    static const penumbra::ShaderLibrary library = penumbra::test::catalogLibrary();
    gl::Program walk = gl::buildProgram({"penumbra/common/fullscreen.vert.glsl", "sample_lists/walk.frag.glsl"},
                                        {{"PENUMBRA_SAMPLE_LISTS_SHADOW_BITS", std::to_string(bits)}}, library);
    const penumbra::SampleListsParams params = penumbra::sampleListsParams(setup, light, options);
    gl::Buffer params_buffer(sizeof params, &params);
    const uint32_t slots = structure.header.accepted;
    gl::Buffer shadow(std::max<size_t>(4, penumbra::shadowBitsBytes(slots, bits)));
    shadow.fill(0u);  // the integrator clears its shadow bits before the light pass
    std::vector<uint32_t> results_init(4 + setup.sample_count, 0u);
    results_init[1] = 0xFFFFFFFFu;
    auto results = gl::Buffer::fromVector(results_init);
    GLuint fbo = 0, vao = 0;
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferParameteri(fbo, GL_FRAMEBUFFER_DEFAULT_WIDTH, static_cast<GLint>(setup.grid_width));
    glNamedFramebufferParameteri(fbo, GL_FRAMEBUFFER_DEFAULT_HEIGHT, static_cast<GLint>(setup.grid_height));
    REQUIRE(glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE);
    glCreateVertexArrays(1, &vao);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, static_cast<GLsizei>(setup.grid_width), static_cast<GLsizei>(setup.grid_height));
    glBindVertexArray(vao);
    walk.use();
    glBindBufferBase(GL_UNIFORM_BUFFER, 0, params_buffer.id());
    const GLuint ssbos[] = {lists.counts.id(), lists.offsets.id(), lists.list_positions.id(), lists.list_ids.id(),
                            lists.sample_slots.id(), shadow.id(), results.id()};
    for (GLuint i = 0; i < 7; ++i) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, i, ssbos[i]);
    // §3.1 multi-pass blocks: llvmpipe stops an invocation after 65 535 loop iterations in total,
    // and each sample costs about 2 + 2 * bits iterations here.
    const uint32_t block_size = 16384 / (1 + bits);
    uint32_t longest = 0;
    for (uint32_t c : structure.counts) longest = std::max(longest, c);
    const uint32_t passes = static_cast<uint32_t>(penumbra::detail::divUp(longest, block_size));
    glUniform1ui(1, block_size);
    for (uint32_t block = 0; block < std::max(passes, 1u); ++block) {
        glUniform1ui(0, block);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }
    MESSAGE("walked lists up to ", longest, " long in ", passes, " passes of ", block_size);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &fbo);
    glDeleteVertexArrays(1, &vao);
    gl::checkErrors("walk lists");

    const auto got = results.download<uint32_t>();
    CHECK(got[0] == 0);
    INFO("first bad slot ", got[1]);
    size_t bad_visits = 0;
    for (uint32_t id = 0; id < setup.sample_count; ++id) {
        const bool accepted = structure.sample_texels[id] < penumbra::kSampleListsRejected;
        bad_visits += got[4 + id] != (accepted ? 1u : 0u);
    }
    CHECK(bad_visits == 0);
    // Expected shadow words from the host twin of the addressing.
    std::vector<uint32_t> expected(shadow.size() / 4, 0u);
    size_t set_bits = 0;
    for (uint32_t slot = 0; slot < slots; ++slot) {
        const uint32_t id = structure.list_ids[slot];
        for (uint32_t k = 0; k < bits; ++k) {
            if ((((id * 2654435761u) ^ (k * 40503u)) & 4u) == 0) continue;
            const auto at = penumbra::shadowBitAddress(slot, k, bits);
            REQUIRE(at.word < expected.size());
            expected[at.word] |= 1u << at.bit;
            ++set_bits;
        }
    }
    if (slots > 8) CHECK(set_bits > 0);
    const auto words = shadow.download<uint32_t>();
    size_t bad_words = 0;
    for (size_t w = 0; w < expected.size(); ++w) bad_words += words[w] != expected[w];
    CHECK(bad_words == 0);
}

// ----- RHI-style replay of a plan (planSampleLists) with raw GL calls, no SampleListBuilder -----

// Programs an engine compiles once from a plan's keys and defines (cached across cases).
GLuint planProgram(const std::string& key, const penumbra::ShaderDefines& defines) {
    static std::map<std::string, gl::Program> cache;
    std::string id = key;
    for (const penumbra::ShaderDefine& d : defines) id += "|" + d.name + "=" + d.value;
    auto it = cache.find(id);
    if (it == cache.end()) it = cache.emplace(id, gl::buildComputeProgram(key, defines)).first;
    return it->second.id();
}

// Records a ScanPlan with raw GL (as tests/scan_test.cpp's replay): counts -> offsets.
void replayScanPlan(const penumbra::ScanPlan& plan, const penumbra::BufferRange& input,
                    const penumbra::BufferRange& output) {
    using penumbra::ScanBuffer;
    if (plan.dispatch_list.empty()) return;
    REQUIRE(plan.input_offset == input.offset);
    REQUIRE(plan.output_offset == output.offset);
    gl::Buffer scratch(std::max<uint64_t>(plan.scratch_bytes, 16));
    scratch.fill(kPoison);  // needs no initialisation
    std::vector<unsigned char> constants(plan.constants_bytes);
    for (size_t i = 0; i < plan.dispatch_list.size(); ++i) {
        std::memcpy(constants.data() + plan.dispatch_list[i].constants.offset, &plan.constants[i],
                    sizeof(penumbra::shared::PenumbraScanConstants));
    }
    gl::Buffer ubo(constants.size(), constants.data());
    auto name = [&](ScanBuffer b) -> GLuint {
        switch (b) {
            case ScanBuffer::Input: return input.buffer;
            case ScanBuffer::Output: return output.buffer;
            case ScanBuffer::Scratch: return scratch.id();
            case ScanBuffer::Constants: return ubo.id();
            default: return 0;
        }
    };
    auto bind = [&](GLenum target, GLuint index, const penumbra::ScanBinding& b) {
        if (b.buffer == ScanBuffer::None) return;
        glBindBufferRange(target, index, name(b.buffer), static_cast<GLintptr>(b.offset),
                          static_cast<GLsizeiptr>(b.size));
    };
    for (const penumbra::ScanDispatch& d : plan.dispatch_list) {
        const char* pass = d.pass == penumbra::ScanPass::Reduce ? "PENUMBRA_SCAN_PASS_REDUCE"
                           : d.pass == penumbra::ScanPass::Scan ? "PENUMBRA_SCAN_PASS_SCAN"
                                                                : "PENUMBRA_SCAN_PASS_TOP";
        const GLuint program =
            planProgram("penumbra/scan/scan.comp.glsl", {{"PENUMBRA_SCAN_PASS", pass},
                                                         {"PENUMBRA_SCAN_GROUP_SIZE", std::to_string(plan.group_size)},
                                                         {"PENUMBRA_SCAN_ITEMS_PER_THREAD",
                                                          std::to_string(plan.items_per_thread)},
                                                         {"PENUMBRA_SCAN_VEC4", d.vec4 ? "1" : "0"}});
        bind(GL_SHADER_STORAGE_BUFFER, PENUMBRA_SCAN_BINDING_INPUT, d.input);
        bind(GL_SHADER_STORAGE_BUFFER, PENUMBRA_SCAN_BINDING_OUTPUT, d.output);
        if (d.vec4) {
            bind(GL_SHADER_STORAGE_BUFFER, PENUMBRA_SCAN_BINDING_INPUT_VEC4, d.input);
            bind(GL_SHADER_STORAGE_BUFFER, PENUMBRA_SCAN_BINDING_OUTPUT_VEC4, d.output);
        }
        bind(GL_SHADER_STORAGE_BUFFER, PENUMBRA_SCAN_BINDING_PARTIALS, d.partials);
        bind(GL_UNIFORM_BUFFER, PENUMBRA_SCAN_BINDING_CONSTANTS, d.constants);
        glUseProgram(program);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        glDispatchCompute(d.grid.x, d.grid.y, 1);
    }
    glFinish();  // the scratch and constants buffers die with this scope
}

// An engine with its own RHI: walks a plan's steps with raw GL calls, its own programs, its own
// constants buffer and sampler, binding resources by the plan's roles.
void replaySampleListsPlan(const penumbra::SampleListsPlan& plan, const penumbra::SampleBufferInput* buffer_input,
                           const penumbra::SampleDepthInput* depth_input, const penumbra::SampleListsBuffers& out) {
    using R = penumbra::SampleListsResource;
    using penumbra::SampleListsStepKind;
    gl::Buffer params(sizeof(penumbra::SampleListsParams));
    GLuint sampler = 0;
    glCreateSamplers(1, &sampler);
    glSamplerParameteri(sampler, GL_TEXTURE_COMPARE_MODE, GL_NONE);
    glSamplerParameteri(sampler, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glSamplerParameteri(sampler, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    auto range = [&](R r) -> penumbra::BufferRange {
        switch (r) {
            case R::Params: return {params.id(), 0, params.size()};
            case R::Frustum: return out.frustum;
            case R::Positions: REQUIRE(buffer_input); return buffer_input->positions;
            case R::Normals: REQUIRE(buffer_input); return buffer_input->normals;
            case R::Counts: return out.counts;
            case R::Offsets: return out.offsets;
            case R::ListPositions: return out.list_positions;
            case R::ListIds: return out.list_ids;
            case R::SampleSlots: return out.sample_slots;
            case R::SampleTexels: return out.sample_texels;
            case R::Header: return out.header;
            default: FAIL("no buffer for resource ", penumbra::sampleListsResourceName(r)); return {};
        }
    };
    for (const penumbra::SampleListsStep& step : plan.steps) {
        switch (step.kind) {
            case SampleListsStepKind::Upload: {
                const penumbra::BufferRange r = range(step.resource);
                const void* data = step.resource == R::Params ? static_cast<const void*>(&plan.params)
                                                              : static_cast<const void*>(&plan.frustum);
                glNamedBufferSubData(r.buffer, GLintptr(r.offset), GLsizeiptr(step.bytes), data);
                break;
            }
            case SampleListsStepKind::Clear: {
                const penumbra::BufferRange r = range(step.resource);
                glClearNamedBufferSubData(r.buffer, GL_R32UI, GLintptr(r.offset + uint64_t(step.first_word) * 4),
                                          GLsizeiptr(uint64_t(step.words) * 4), GL_RED_INTEGER, GL_UNSIGNED_INT,
                                          &step.value);
                break;
            }
            case SampleListsStepKind::Dispatch: {
                const penumbra::SampleListsProgram* program = plan.program(step.kernel);
                REQUIRE(program);
                glUseProgram(planProgram(program->key, program->defines));
                for (uint32_t i = 0; i < step.binding_count; ++i) {
                    const penumbra::SampleListsBinding& b = step.bindings[i];
                    if (b.kind == penumbra::SampleListsBindingKind::Texture) {
                        REQUIRE(depth_input);
                        glBindTextureUnit(b.point, b.resource == R::DepthTexture ? depth_input->depth_texture
                                                                                 : depth_input->normal_texture);
                        glBindSampler(b.point, sampler);
                        continue;
                    }
                    const penumbra::BufferRange r = range(b.resource);
                    REQUIRE(r.size >= b.bytes);
                    const GLenum target = b.kind == penumbra::SampleListsBindingKind::UniformBuffer
                                              ? GL_UNIFORM_BUFFER
                                              : GL_SHADER_STORAGE_BUFFER;
                    glBindBufferRange(target, b.point, r.buffer, GLintptr(r.offset), GLsizeiptr(b.bytes));
                }
                glDispatchCompute(step.grid.x, step.grid.y, 1);
                break;
            }
            case SampleListsStepKind::Scan:
                REQUIRE(plan.scan.n == step.elements);
                replayScanPlan(plan.scan, range(step.resource), range(step.output));
                break;
            case SampleListsStepKind::Barrier: glMemoryBarrier(static_cast<GLbitfield>(step.barriers)); break;
        }
    }
    glFinish();
    glDeleteSamplers(1, &sampler);
    glUseProgram(0);
    gl::checkErrors("plan replay");
}

// Every output of a build in one buffer at aligned, non-zero offsets (the plan's scan bindings
// are absolute offsets).
struct ArenaLists {
    gl::Buffer arena;
    penumbra::SampleListsBuffers ranges;
    ArenaLists(const SampleListsSetup& s, uint64_t alignment) {
        uint64_t at = alignment;
        auto take = [&](uint64_t bytes) {
            const penumbra::BufferRange r{0, at, bytes};
            at += penumbra::detail::alignUp(std::max<uint64_t>(bytes, 4), alignment);
            return r;
        };
        penumbra::BufferRange* all[] = {&ranges.counts,       &ranges.offsets,       &ranges.list_positions,
                                        &ranges.list_ids,     &ranges.sample_slots,  &ranges.sample_texels,
                                        &ranges.header,       &ranges.frustum};
        const uint64_t bytes[] = {s.counts_bytes,       s.offsets_bytes,       s.list_positions_bytes,
                                  s.list_ids_bytes,     s.sample_slots_bytes,  s.sample_texels_bytes,
                                  s.header_bytes,       sizeof(penumbra::SampleListsFrustum)};
        for (int i = 0; i < 8; ++i) *all[i] = take(bytes[i]);
        arena = gl::Buffer(at);
        arena.fill(kPoison);
        for (penumbra::BufferRange* r : all) r->buffer = arena.id();
    }
};

// Executor build, then the plan replayed into its own (poisoned) buffers: the same lists, header
// and frustum bytes, and both equal to the CPU twin (for the fitted frustum when fitting).
// Returns the accepted count.
uint32_t checkReplay(const SampleListsSetup& setup, const SampleListsLight& light, const SampleListsOptions& options,
                     const penumbra::SampleListsBuild& build, const penumbra::SampleListsBindingPoints* bindings,
                     const penumbra::SampleBufferInput* buffer_input, const penumbra::SampleDepthInput* depth_input,
                     const std::function<SampleListsCpu(const SampleListsLight&)>& cpu_build) {
    const penumbra::SampleListsInputKind kind =
        depth_input ? penumbra::SampleListsInputKind::Depth : penumbra::SampleListsInputKind::Buffer;
    GpuLists executor_lists(setup);
    executor_lists.poison();
    const Status status = depth_input ? buildChecked(setup, light, *depth_input, executor_lists.ids(), options, build)
                                      : buildChecked(setup, light, *buffer_input, executor_lists.ids(), options, build);
    REQUIRE(status == Status::Ok);
    const SampleListsCpu executor = penumbra::downloadSampleLists(setup, executor_lists.ids());

    GLint ssbo_alignment = 0, ubo_alignment = 0;
    glGetIntegerv(GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT, &ssbo_alignment);
    glGetIntegerv(GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT, &ubo_alignment);
    ArenaLists replay_lists(setup, uint64_t(std::max({ssbo_alignment, ubo_alignment, 16})));
    penumbra::SampleListsPlanOptions plan_options =
        builder().planOptions(replay_lists.ranges.counts.offset, replay_lists.ranges.offsets.offset);
    if (bindings) plan_options.bindings = *bindings;
    const penumbra::SampleListsPlan plan = penumbra::planSampleLists(
        setup, light, options, build, kind, depth_input ? &depth_input->view : nullptr, plan_options);
    replaySampleListsPlan(plan, buffer_input, depth_input, replay_lists.ranges);
    const SampleListsCpu replayed = penumbra::downloadSampleLists(setup, replay_lists.ranges);
    CHECK(penumbra::sampleListsDifference(replayed, executor) == "");

    // Header (counters, fit keys, statistics; untouched words still poisoned alike) and frustum.
    const penumbra::SampleListsHeader h_exec = penumbra::SampleListBuilder::readHeader(executor_lists.ids().header);
    const penumbra::SampleListsHeader h_replay = penumbra::SampleListBuilder::readHeader(replay_lists.ranges.header);
    CHECK(std::memcmp(&h_exec, &h_replay, sizeof h_exec) == 0);
    const penumbra::SampleListsFrustum f_exec = penumbra::SampleListBuilder::readFrustum(executor_lists.ids().frustum);
    const penumbra::SampleListsFrustum f_replay = penumbra::SampleListBuilder::readFrustum(replay_lists.ranges.frustum);
    CHECK(std::memcmp(&f_exec, &f_replay, sizeof f_exec) == 0);
    if (!build.fit_frustum) {
        // Without the fit both hold the block their Upload step wrote; nothing may overwrite it.
        CHECK(std::memcmp(&f_exec, &plan.frustum, sizeof f_exec) == 0);
        CHECK(std::memcmp(&f_replay, &plan.frustum, sizeof f_replay) == 0);
    }

    SampleListsLight used = light;
    if (build.fit_frustum) used.view_projection = f_replay.view_projection;
    const SampleListsCpu cpu = cpu_build(used);
    if (h_exec.accepted != h_replay.accepted) {
        // Seen on NVIDIA (H200, 580.159), moved bindings without the fit: the replay into one arena
        // buffer accepted fewer samples than the executor and its frustum bytes differed. Replay
        // again into separate buffers (the executor's layout) and into an arena with the default
        // binding points, to tell the arena, the binding points and the plan apart; name who
        // agrees with the CPU twin, and whether classification or counting went wrong.
        auto classified = [](const penumbra::SampleListsHeader& h) {
            uint64_t sum = h.accepted;
            for (uint32_t r : h.rejected) sum += r;
            return sum;
        };
        GpuLists separate_lists(setup);
        separate_lists.poison();
        penumbra::SampleListsPlanOptions separate_options = builder().planOptions(0, 0);
        if (bindings) separate_options.bindings = *bindings;
        const penumbra::SampleListsPlan separate_plan = penumbra::planSampleLists(
            setup, light, options, build, kind, depth_input ? &depth_input->view : nullptr, separate_options);
        replaySampleListsPlan(separate_plan, buffer_input, depth_input, separate_lists.ids());
        const penumbra::SampleListsHeader h_separate = penumbra::SampleListBuilder::readHeader(separate_lists.ids().header);
        ArenaLists default_lists(setup, uint64_t(std::max({ssbo_alignment, ubo_alignment, 16})));
        const penumbra::SampleListsPlan default_plan = penumbra::planSampleLists(
            setup, light, options, build, kind, depth_input ? &depth_input->view : nullptr,
            builder().planOptions(default_lists.ranges.counts.offset, default_lists.ranges.offsets.offset));
        replaySampleListsPlan(default_plan, buffer_input, depth_input, default_lists.ranges);
        const penumbra::SampleListsHeader h_default = penumbra::SampleListBuilder::readHeader(default_lists.ranges.header);
        const penumbra::SampleListsFrustum f_default = penumbra::SampleListBuilder::readFrustum(default_lists.ranges.frustum);
        MESSAGE("accepted (of classified): executor ", h_exec.accepted, " (", classified(h_exec),
                "), replay into one arena ", h_replay.accepted, " (", classified(h_replay),
                "), into separate buffers ", h_separate.accepted, " (", classified(h_separate),
                "), into an arena with the default binding points ", h_default.accepted, " (", classified(h_default),
                "), CPU twin ", cpu.header.accepted, "; frustum bytes: arena replay ",
                std::memcmp(&f_replay, &f_exec, sizeof f_exec) == 0 ? "==" : "!=", " executor, default-binding replay ",
                std::memcmp(&f_default, &f_exec, sizeof f_exec) == 0 ? "==" : "!=", " executor");
    }
    PENUMBRA_CHECK_BITWISE("sample lists GPU == CPU twin", penumbra::sampleListsDifference(replayed, cpu) == "");
    if (build.statistics) {
        CHECK(penumbra::sampleListStatisticsFromHeader(setup, h_replay) == penumbra::sampleListStatisticsCpu(cpu));
    }
    return cpu.header.accepted;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

TEST_CASE("setup, parameters and shadow-bit sizing validate and name bad values") {
    CHECK_THROWS_WITH_AS(penumbra::sampleListsSetup(0, 4, 10), doctest::Contains("grid width 0"), penumbra::Error);
    CHECK_THROWS_WITH_AS(penumbra::sampleListsSetup(4, 0, 10), doctest::Contains("grid height 0"), penumbra::Error);
    CHECK_THROWS_WITH_AS(penumbra::sampleListsSetup(16385, 4, 10), doctest::Contains("grid width 16385"),
                         penumbra::Error);
    CHECK_THROWS_WITH_AS(penumbra::sampleListsSetup(4, 100000, 10), doctest::Contains("grid height 100000"),
                         penumbra::Error);
    CHECK_THROWS_WITH_AS(penumbra::sampleListsSetup(4, 4, 0x100000000ull), doctest::Contains("sample count 4294967296"),
                         penumbra::Error);
    const SampleListsSetup s = penumbra::sampleListsSetup(7, 5, 1000);
    CHECK(s.lists == 35);
    CHECK(s.counts_bytes == 140);
    CHECK(s.offsets_bytes == 140);
    CHECK(s.list_positions_bytes == 16000);
    CHECK(s.list_ids_bytes == 4000);
    CHECK(s.sample_slots_bytes == 4000);
    CHECK(s.sample_texels_bytes == 4000);
    CHECK(s.header_bytes == 96);
    CHECK(s.sample_groups.groups == 4);
    CHECK(s.list_groups.groups == 1);
    const SampleListsSetup big = penumbra::sampleListsSetup(16384, 16384, 65535ull * 256 + 1);
    CHECK(big.sample_groups.groups == 65536);
    CHECK(uint64_t(big.sample_groups.x) * big.sample_groups.y >= 65536);

    SampleListsLight light = pointLight();
    light.view_projection[2][1] = kNaN;
    CHECK_THROWS_WITH_AS(penumbra::sampleListsParams(s, light), doctest::Contains("view_projection[2][1]"),
                         penumbra::Error);
    light = pointLight();
    light.light.w = 0.5f;
    CHECK_THROWS_WITH_AS(penumbra::sampleListsParams(s, light), doctest::Contains("light.w = 0.5"), penumbra::Error);
    light.light = glm::vec4(0.0f);
    CHECK_THROWS_WITH_AS(penumbra::sampleListsParams(s, light), doctest::Contains("direction (0, 0, 0)"),
                         penumbra::Error);
    light.light = glm::vec4(kInf, 0.0f, 0.0f, 1.0f);
    CHECK_THROWS_AS(penumbra::sampleListsParams(s, light), penumbra::Error);
    penumbra::SampleListsView view;
    view.width = 10;
    view.height = 10;
    CHECK_THROWS_WITH_AS(penumbra::sampleListsParams(s, pointLight(), {}, &view),
                         doctest::Contains("does not match the setup's sample count 1000"), penumbra::Error);
    CHECK_THROWS_WITH_AS(penumbra::buildSampleListsCpu(s, pointLight(), nullptr, nullptr),
                         doctest::Contains("positions is null"), penumbra::Error);
    std::vector<glm::vec4> positions(1000, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
    CHECK_THROWS_WITH_AS(penumbra::buildSampleListsCpu(s, pointLight(), positions.data(), nullptr),
                         doctest::Contains("normals is null"), penumbra::Error);
    CHECK_NOTHROW(penumbra::buildSampleListsCpu(s, pointLight(), positions.data(), nullptr,
                                                SampleListsOptions{false, LightDepthRange::MinusOneToOne}));

    // Shadow bits: stride, words, addresses (closed form).
    const uint32_t strides[] = {0, 1, 2, 4, 4, 8, 8, 8, 8, 16, 16, 16, 16, 16, 16, 16, 16};
    for (uint32_t bits = 1; bits <= 16; ++bits) CHECK(penumbra::shadowStrideBits(bits) == strides[bits]);
    for (uint32_t bits = 17; bits <= 200; ++bits) CHECK(penumbra::shadowStrideBits(bits) == (bits + 31) / 32 * 32);
    CHECK_THROWS_WITH_AS(penumbra::shadowStrideBits(0), doctest::Contains("bits per sample 0"), penumbra::Error);
    CHECK_THROWS_AS(penumbra::shadowStrideBits(65537), penumbra::Error);
    CHECK(penumbra::shadowBitsWords(0, 1) == 0);
    CHECK(penumbra::shadowBitsWords(33, 1) == 2);
    CHECK(penumbra::shadowBitsWords(10, 5) == 3);  // stride 8: 4 slots per word
    CHECK(penumbra::shadowBitsWords(10, 40) == 20);
    CHECK(penumbra::shadowBitsBytes(10, 128) == 160);
    CHECK_THROWS_AS(penumbra::shadowBitsWords(0xFFFFFF00u, 1024), penumbra::Error);
    CHECK(penumbra::shadowBitAddress(37, 0, 1).word == 1);
    CHECK(penumbra::shadowBitAddress(37, 0, 1).bit == 5);
    CHECK(penumbra::shadowBitAddress(5, 3, 5).word == 1);
    CHECK(penumbra::shadowBitAddress(5, 3, 5).bit == 11);
    CHECK(penumbra::shadowBitAddress(3, 35, 40).word == 7);
    CHECK(penumbra::shadowBitAddress(3, 35, 40).bit == 3);
    // Every (slot, bit) has its own bit: no two collide.
    for (uint32_t bits : {1u, 3u, 5u, 16u, 17u, 40u, 64u}) {
        std::vector<uint32_t> words(penumbra::shadowBitsWords(50, bits), 0u);
        size_t collisions = 0;
        for (uint32_t slot = 0; slot < 50; ++slot) {
            for (uint32_t k = 0; k < bits; ++k) {
                const auto at = penumbra::shadowBitAddress(slot, k, bits);
                REQUIRE(at.word < words.size());
                collisions += (words[at.word] >> at.bit) & 1u;
                words[at.word] |= 1u << at.bit;
            }
        }
        CHECK(collisions == 0);
    }
}

TEST_CASE("listedPositions: the lists' position for every listed sample, the fallback for the rest") {
    SampleListsCpu lists;
    lists.sample_slots = {1u, penumbra::kSampleListsNoSlot, 0u, 1u, 7u};
    lists.list_ids = {2u, 0u};
    lists.list_positions = {glm::vec4(1, 2, 3, 1), glm::vec4(4, 5, 6, 0)};
    const std::vector<glm::vec4> fallback = {glm::vec4(-1), glm::vec4(-2), glm::vec4(-3), glm::vec4(-4), glm::vec4(-5)};
    const std::vector<glm::vec4> out = penumbra::listedPositions(lists, fallback);
    REQUIRE(out.size() == 5);
    CHECK(out[0] == glm::vec4(4, 5, 6, 1));  // slot 1 holds sample 0; w is always 1
    CHECK(out[1] == glm::vec4(-2));          // not listed
    CHECK(out[2] == glm::vec4(1, 2, 3, 1));  // slot 0 holds sample 2
    CHECK(out[3] == glm::vec4(-4));          // slot 1 names sample 0, not 3: broken, fallback
    CHECK(out[4] == glm::vec4(-5));          // slot 7 is past the lists
    CHECK(penumbra::listedPositions(lists, {glm::vec4(9)}) == std::vector<glm::vec4>{glm::vec4(4, 5, 6, 1)});
}

TEST_CASE("texel borders, frustum, near/far, NaN/Inf, background and back-facing follow the rules (closed form)") {
    context();
    // Directional light straight down -z onto an 8 x 4 grid: view = translate(0, 0, -5) exactly,
    // ortho [-1, 1]^2, near 1, far 9, so u = (x + 1) / 2 and v = (y + 1) / 2 are exact for
    // dyadic x, y: x = -1 + k / 4 lies exactly on texel border k of W = 8.
    SampleListsLight light;
    light.view_projection = glm::ortho(-1.0f, 1.0f, -1.0f, 1.0f, 1.0f, 9.0f) *
                            glm::lookAt(glm::vec3(0.0f, 0.0f, 5.0f), glm::vec3(0.0f), glm::vec3(0.0f, 1.0f, 0.0f));
    light.light = glm::vec4(0.0f, 0.0f, 1.0f, 0.0f);
    const glm::vec4 up(0.0f, 0.0f, 1.0f, 0.0f);
    Samples s;
    std::vector<uint32_t> expected;
    auto add = [&](glm::vec4 p, glm::vec4 n, uint32_t e) {
        s.positions.push_back(p);
        s.normals.push_back(n);
        expected.push_back(e);
    };
    const uint32_t W = 8, H = 4;
    for (uint32_t k = 0; k <= W; ++k) {
        for (uint32_t j = 0; j <= H; ++j) {
            const float x = -1.0f + static_cast<float>(k) / 4.0f, y = -1.0f + static_cast<float>(j) / 2.0f;
            // Exactly on the border: the texel to the right / top, the last one for u == 1.
            add({x, y, 0.0f, 1.0f}, up, std::min(j, H - 1) * W + std::min(k, W - 1));
            // Just below the border: the texel to the left / bottom, outside below 0.
            const float xm = x - 1e-5f, ym = y - 1e-5f;
            const bool out = k == 0 || j == 0;
            add({xm, ym, 0.0f, 1.0f}, up, out ? code(SampleRejection::Outside) : (j - 1) * W + (k - 1));
            // Just above: outside past u == 1.
            const bool out_above = k == W || j == H;
            add({x + 1e-5f, y + 1e-5f, 0.0f, 1.0f}, up,
                out_above ? code(SampleRejection::Outside) : std::min(j, H - 1) * W + std::min(k, W - 1));
        }
    }
    // Near/far (light view z = z - 5; near 1 -> z = 4, far 9 -> z = -4), closed planes.
    add({0.1f, 0.1f, 4.0f, 1.0f}, up, 4 * 8 / 2 + 4);  // on the near plane: inside (texel (4, 2))
    add({0.1f, 0.1f, -4.0f, 1.0f}, up, 2 * 8 + 4);     // on the far plane: inside
    add({0.1f, 0.1f, 4.5f, 1.0f}, up, code(SampleRejection::Depth));
    add({0.1f, 0.1f, -4.5f, 1.0f}, up, code(SampleRejection::Depth));
    // Non-finite, background and precedence.
    add({kNaN, 0.1f, 0.0f, 1.0f}, up, code(SampleRejection::NonFinite));
    add({0.1f, kInf, 0.0f, 1.0f}, up, code(SampleRejection::NonFinite));
    add({0.1f, 0.1f, -kInf, 1.0f}, up, code(SampleRejection::NonFinite));
    add({0.1f, 0.1f, 0.0f, 1.0f}, {kNaN, 0.0f, 1.0f, 0.0f}, code(SampleRejection::NonFinite));
    add({kNaN, kNaN, kNaN, 0.0f}, up, code(SampleRejection::Background));
    add({0.1f, 0.1f, 0.0f, 0.0f}, up, code(SampleRejection::Background));
    add({3.0f, 0.1f, 0.0f, 1.0f}, -up, code(SampleRejection::Outside));     // outside beats back-facing
    add({0.1f, 0.1f, 6.0f, 1.0f}, -up, code(SampleRejection::Depth));       // depth beats back-facing
    // Light-facing (Fig. 2): dot(n, to_light) <= 0 is back-facing, including 0.
    add({0.1f, 0.1f, 0.0f, 1.0f}, -up, code(SampleRejection::BackFacing));
    add({0.1f, 0.1f, 0.0f, 1.0f}, {1.0f, 0.0f, 0.0f, 0.0f}, code(SampleRejection::BackFacing));
    add({0.1f, 0.1f, 0.0f, 1.0f}, {0.0f, 0.0f, 1e-30f, 0.0f}, 2 * 8 + 4);
    // Far outside: the transform overflows to Inf.
    add({3e38f, 3e38f, 0.0f, 1.0f}, up, code(SampleRejection::Outside));

    const SampleListsSetup setup = penumbra::sampleListsSetup(W, H, s.positions.size());
    const SampleListsOptions options;
    const SampleListsCpu cpu = cpuBuild(setup, light, s, options);
    const SampleListsCpu gpu = gpuBuild(setup, light, s, options);
    for (size_t id = 0; id < expected.size(); ++id) {
        CAPTURE(id);
        CAPTURE(s.positions[id].x);
        CAPTURE(s.positions[id].y);
        CHECK(cpu.sample_texels[id] == expected[id]);
        PENUMBRA_CHECK_BITWISE("sample lists: GPU texel codes follow the float border rule", gpu.sample_texels[id] == expected[id]);
    }
    checkStructure(setup, cpu, s.positions.data(), nullptr);
    checkStructure(setup, gpu, s.positions.data(), nullptr);
    PENUMBRA_CHECK_BITWISE("sample lists GPU == CPU twin", penumbra::sampleListsDifference(gpu, cpu) == "");
    // The CPU twin orders every list by sample id.
    for (uint32_t list = 0; list < setup.lists; ++list) {
        for (uint32_t k = 1; k < cpu.counts[list]; ++k) {
            CHECK(cpu.list_ids[cpu.offsets[list] + k - 1] < cpu.list_ids[cpu.offsets[list] + k]);
        }
    }

    // Switches: no culling keeps back-facing and NaN-normal samples; Unclipped keeps near/far ones.
    SampleListsOptions keep_all{false, LightDepthRange::Unclipped};
    const SampleListsCpu cpu_all = cpuBuild(setup, light, s, keep_all);
    const SampleListsCpu gpu_all = gpuBuild(setup, light, s, keep_all);
    CHECK(cpu_all.header.rejected[uint32_t(SampleRejection::BackFacing)] == 0);
    CHECK(cpu_all.header.rejected[uint32_t(SampleRejection::Depth)] == 0);
    CHECK(cpu_all.header.rejected[uint32_t(SampleRejection::NonFinite)] == 3);
    // 2 back-facing + 2 beyond near/far + 1 NaN normal + 1 beyond far and back-facing.
    CHECK(cpu_all.header.accepted == cpu.header.accepted + 6);
    PENUMBRA_CHECK_BITWISE("sample lists GPU == CPU twin", penumbra::sampleListsDifference(gpu_all, cpu_all) == "");
}

TEST_CASE("GPU lists equal the CPU twin and the invariants on random samples across work-group edges") {
    context();
    const uint32_t seed = testSeed();
    std::mt19937 rng(seed);
    const std::pair<uint32_t, uint32_t> grids[] = {{1, 1}, {7, 5}, {64, 64}, {300, 1}, {257, 129}};
    size_t decided_total = 0, accepted_total = 0;
    int round = 0;
    for (size_t n : {size_t(0), size_t(1), size_t(255), size_t(256), size_t(257), size_t(65537)}) {
        for (int light_kind = 0; light_kind < 2; ++light_kind) {
            const auto grid = grids[(round++) % 5];
            CAPTURE(n);
            CAPTURE(light_kind);
            CAPTURE(grid.first);
            CAPTURE(grid.second);
            const SampleListsLight light = light_kind == 0 ? pointLight() : directionalLight();
            const SampleListsSetup setup = penumbra::sampleListsSetup(grid.first, grid.second, n);
            const Samples samples = randomSamples(rng, n);
            SampleListsOptions options;
            options.cull_back_facing = (round % 3) != 0;
            options.depth_range = (round % 4) == 1 ? LightDepthRange::Unclipped : LightDepthRange::MinusOneToOne;
            const SampleListsCpu cpu = cpuBuild(setup, light, samples, options);
            const SampleListsCpu gpu = gpuBuild(setup, light, samples, options);
            const auto oracle = oracleCodes(setup, light, options, samples);
            decided_total += checkStructure(setup, cpu, samples.positions.data(), &oracle);
            checkStructure(setup, gpu, samples.positions.data(), &oracle);
            PENUMBRA_CHECK_BITWISE("sample lists GPU == CPU twin", penumbra::sampleListsDifference(gpu, cpu) == "");
            accepted_total += cpu.header.accepted;
        }
    }
    MESSAGE("oracle decided ", decided_total, " samples; ", accepted_total, " accepted");
    CHECK(decided_total > 100000);
    CHECK(accepted_total > 10000);
}

TEST_CASE("GPU and CPU agree bit for bit on samples within a few ULPs of texel borders") {
    context();
    const uint32_t seed = testSeed(1);
    std::mt19937 rng(seed);
    for (const SampleListsLight& light : {pointLight(), directionalLight()}) {
        for (auto grid : {std::pair<uint32_t, uint32_t>{64, 64}, {100, 37}, {1024, 3}}) {
            const uint32_t W = grid.first, H = grid.second;
            // Aim at border points in light-texture space, unproject with the light's inverse,
            // then nudge the world position by a few ULPs.
            const glm::mat4 t_matrix = penumbra::lightTextureMatrix(light.view_projection, LightDepthRange::MinusOneToOne);
            const glm::dmat4 inverse = glm::inverse(glm::dmat4(t_matrix));
            std::uniform_int_distribution<uint32_t> bx(0, W), by(0, H), ulps(0, 8);
            std::uniform_real_distribution<double> depth(0.2, 0.8), along(0.0, 1.0);
            std::uniform_int_distribution<int> which(0, 2);
            Samples s;
            const size_t n = 20000;
            for (size_t i = 0; i < n; ++i) {
                double u = double(bx(rng)) / W, v = double(by(rng)) / H;
                const int w = which(rng);  // 0: corner, 1: vertical border, 2: horizontal border
                if (w == 1) v = along(rng);
                if (w == 2) u = along(rng);
                const glm::dvec4 h = inverse * glm::dvec4(u, v, depth(rng), 1.0);
                glm::vec3 p(h / h.w);
                for (int c = 0; c < 3; ++c) {
                    for (uint32_t k = ulps(rng); k > 0; --k) {
                        p[c] = std::nextafter(p[c], (rng() & 1) ? kInf : -kInf);
                    }
                }
                s.positions.emplace_back(p, 1.0f);
                s.normals.emplace_back(glm::normalize(glm::vec3(light.light)), 0.0f);  // front-facing
            }
            const SampleListsSetup setup = penumbra::sampleListsSetup(W, H, n);
            const SampleListsOptions options;
            const SampleListsCpu cpu = cpuBuild(setup, light, s, options);
            const SampleListsCpu gpu = gpuBuild(setup, light, s, options);
            PENUMBRA_CHECK_BITWISE("sample lists GPU == CPU twin", penumbra::sampleListsDifference(gpu, cpu) == "");
            checkStructure(setup, gpu, s.positions.data(), nullptr);
            // The test has teeth: many samples sit exactly on a border in float arithmetic.
            const penumbra::SampleListsParams params = penumbra::sampleListsParams(setup, light, options);
            size_t on_border = 0;
            for (const glm::vec4& p : s.positions) {
                const glm::vec4 t = penumbra::detail::transformPoint(params.light_texture, p.x, p.y, p.z);
                const float gx = (t.x / t.w) * float(W);
                on_border += t.w > 0 && gx == std::floor(gx);
            }
            MESSAGE("grid ", W, "x", H, ": ", on_border, " of ", n, " samples exactly on a vertical border, ",
                    cpu.header.accepted, " accepted");
            CHECK(on_border > 100);
        }
    }
}

TEST_CASE("depth-texture input: GPU equals the CPU twin") {
    context();
    const uint32_t seed = testSeed(2);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f), d01(0.0f, 1.0f);
    for (auto size : {std::pair<uint32_t, uint32_t>{37, 23}, {64, 64}, {300, 2}}) {
        for (int variant = 0; variant < 4; ++variant) {
            const uint32_t vw = size.first, vh = size.second;
            CAPTURE(vw);
            CAPTURE(vh);
            CAPTURE(variant);
            penumbra::SampleListsView view;
            view.width = vw;
            view.height = vh;
            view.depth_zero_to_one = variant & 1;
            const float aspect = 1.0f;  // not the pixel aspect: keeps the 300 x 2 strip on the scene
            const glm::mat4 projection = view.depth_zero_to_one
                                             ? glm::perspectiveRH_ZO(glm::radians(50.0f), aspect, 0.5f, 12.0f)
                                             : glm::perspective(glm::radians(50.0f), aspect, 0.5f, 12.0f);
            const glm::mat4 camera =
                projection * glm::lookAt(glm::vec3(0.0f, 3.0f, 5.0f), glm::vec3(0.0f), glm::vec3(0, 1, 0));
            view.inverse_view_projection = glm::inverse(camera);
            std::vector<float> depth(size_t(vw) * vh);
            std::vector<glm::vec4> normals(depth.size());
            for (size_t i = 0; i < depth.size(); ++i) {
                const float r = d01(rng);
                depth[i] = r < 0.1f ? 1.0f : r < 0.12f ? 0.0f : std::pow(d01(rng), 0.2f);
                normals[i] = glm::vec4(glm::normalize(glm::vec3(unit(rng), unit(rng) + 1.5f, unit(rng))), 0.0f);
            }
            gl::Texture depth_texture(GL_TEXTURE_2D), normal_texture(GL_TEXTURE_2D);
            glTextureStorage2D(depth_texture.id(), 1, GL_DEPTH_COMPONENT32F, GLsizei(vw), GLsizei(vh));
            glTextureSubImage2D(depth_texture.id(), 0, 0, 0, GLsizei(vw), GLsizei(vh), GL_DEPTH_COMPONENT, GL_FLOAT,
                                depth.data());
            glTextureStorage2D(normal_texture.id(), 1, GL_RGBA32F, GLsizei(vw), GLsizei(vh));
            glTextureSubImage2D(normal_texture.id(), 0, 0, 0, GLsizei(vw), GLsizei(vh), GL_RGBA, GL_FLOAT,
                                normals.data());
            const SampleListsLight light = (variant & 2) ? directionalLight() : pointLight();
            SampleListsOptions options;
            options.cull_back_facing = variant != 3;
            const SampleListsSetup setup = penumbra::sampleListsSetup(97, 61, depth.size());
            const SampleListsCpu cpu = penumbra::buildSampleListsCpu(setup, light, view, depth.data(), normals.data(), options);
            GpuLists lists(setup);
            lists.poison();
            REQUIRE(buildChecked(setup, light, penumbra::SampleDepthInput{depth_texture.id(), normal_texture.id(), view},
                                 lists.ids(), options) == Status::Ok);
            const SampleListsCpu gpu = penumbra::downloadSampleLists(setup, lists.ids());
            gl::checkErrors("depth-input build");
            PENUMBRA_CHECK_BITWISE("sample lists GPU == CPU twin", penumbra::sampleListsDifference(gpu, cpu) == "");
            checkStructure(setup, gpu, nullptr, nullptr);
            // Reconstructed positions: the twin's are within float error of a double unprojection.
            size_t far_off = 0;
            for (uint32_t id = 0; id < setup.sample_count; ++id) {
                if (depth[id] == 1.0f) {
                    CHECK(cpu.sample_texels[id] == code(SampleRejection::Background));
                    continue;
                }
                const uint32_t slot = cpu.sample_slots[id];
                if (slot == penumbra::kSampleListsNoSlot) continue;
                const double z = view.depth_zero_to_one ? depth[id] : 2.0 * depth[id] - 1.0;
                const glm::dvec4 h = glm::dmat4(view.inverse_view_projection) *
                                     glm::dvec4((id % vw + 0.5) / vw * 2 - 1, (id / vw + 0.5) / vh * 2 - 1, z, 1.0);
                const glm::dvec3 p = glm::dvec3(h) / h.w;
                far_off += glm::length(p - glm::dvec3(cpu.list_positions[slot])) > 1e-3 * (1.0 + glm::length(p));
            }
            CHECK(far_off == 0);
            CHECK(cpu.header.accepted > 0);
            CHECK(cpu.header.rejected[uint32_t(SampleRejection::Background)] > 0);
        }
    }
}

TEST_CASE("zero samples give an empty structure") {
    context();
    const SampleListsSetup setup = penumbra::sampleListsSetup(13, 7, 0);
    CHECK(setup.list_positions_bytes == 0);
    const SampleListsCpu cpu = cpuBuild(setup, pointLight(), Samples{}, {});
    GpuLists lists(setup);
    lists.poison();
    REQUIRE(buildChecked(setup, pointLight(), penumbra::SampleBufferInput{}, lists.ids()) == Status::Ok);
    const SampleListsCpu gpu = penumbra::downloadSampleLists(setup, lists.ids());
    CHECK(gpu.counts == std::vector<uint32_t>(91, 0u));
    CHECK(gpu.offsets == std::vector<uint32_t>(91, 0u));
    CHECK(gpu.header.accepted == 0);
    for (uint32_t r : gpu.header.rejected) CHECK(r == 0);
    CHECK(penumbra::sampleListsDifference(gpu, cpu) == "");
    const penumbra::SampleListStatistics stats = gpuStatistics(setup, lists);
    CHECK(stats == penumbra::sampleListStatisticsCpu(cpu));
    CHECK(stats.occupied_lists == 0);
    CHECK(stats.averageOccupiedLength() == 0.0);
    const auto fit = gpuFit(setup, pointLight(), penumbra::SampleBufferInput{}, lists);
    CHECK_FALSE(fit.valid);
    CHECK(fit.view_projection == pointLight().view_projection);
    gl::checkErrors("zero samples");
}

TEST_CASE("all samples in one texel: a list of 2^20 samples, walked from a fragment shader") {
    context();
    const uint32_t seed = testSeed(3);
    std::mt19937 rng(seed);
    const SampleListsLight light = directionalLight();
    const uint32_t n = 1u << 20;
    // Points inside one texel of a 32 x 32 grid: unproject random (u, v) inside texel (11, 20).
    const glm::dmat4 inverse =
        glm::inverse(glm::dmat4(penumbra::lightTextureMatrix(light.view_projection, LightDepthRange::MinusOneToOne)));
    std::uniform_real_distribution<double> inside(0.1, 0.9), depth(0.2, 0.8);
    Samples s;
    s.positions.resize(n);
    s.normals.assign(n, glm::vec4(glm::vec3(light.light), 0.0f));
    for (uint32_t i = 0; i < n; ++i) {
        const glm::dvec4 h = inverse * glm::dvec4((11 + inside(rng)) / 32, (20 + inside(rng)) / 32, depth(rng), 1.0);
        s.positions[i] = glm::vec4(glm::vec3(h / h.w), 1.0f);
    }
    const SampleListsSetup setup = penumbra::sampleListsSetup(32, 32, n);
    const SampleListsOptions options;
    const SampleListsCpu cpu = cpuBuild(setup, light, s, options);
    GpuLists lists(setup);
    const SampleListsCpu gpu = gpuBuild(setup, light, s, options, &lists);
    CHECK(cpu.counts[20 * 32 + 11] == n);
    CHECK(gpu.counts[20 * 32 + 11] == n);
    PENUMBRA_CHECK_BITWISE("sample lists GPU == CPU twin", penumbra::sampleListsDifference(gpu, cpu) == "");
    checkStructure(setup, gpu, s.positions.data(), nullptr);
    const auto stats = gpuStatistics(setup, lists);
    CHECK(stats.max_list_length == n);
    CHECK(stats.occupied_lists == 1);
    CHECK(stats == penumbra::sampleListStatisticsCpu(gpu));
    walkLists(setup, light, options, lists, gpu, 1);
}

TEST_CASE("the GLSL list API walks every list from a fragment shader; shadow bits land where the host says") {
    context();
    const uint32_t seed = testSeed(4);
    std::mt19937 rng(seed);
    for (uint32_t bits : {1u, 5u, 40u}) {
        for (const SampleListsLight& light : {pointLight(), directionalLight()}) {
            // A fine grid (short lists) and a coarse one (lists span several blocks of a pass).
            const bool coarse = light.light.w == 0.0f;
            const SampleListsSetup setup = penumbra::sampleListsSetup(coarse ? 4 : 61, coarse ? 3 : 45, 30000);
            const Samples samples = randomSamples(rng, setup.sample_count);
            const SampleListsOptions options;
            GpuLists lists(setup);
            const SampleListsCpu gpu = gpuBuild(setup, light, samples, options, &lists);
            REQUIRE(gpu.header.accepted > 1000);
            walkLists(setup, light, options, lists, gpu, bits);
        }
    }
}

TEST_CASE("bad input: validate() throws penumbra::Error naming the value, build() returns a Status") {
    context();
    const SampleListsSetup setup = penumbra::sampleListsSetup(16, 16, 1000);
    Samples s;
    s.positions.assign(1000, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
    s.normals.assign(1000, glm::vec4(0.0f, 1.0f, 0.0f, 0.0f));
    auto positions = gl::Buffer::fromVector(s.positions);
    auto normals = gl::Buffer::fromVector(s.normals);
    GpuLists lists(setup);
    const penumbra::SampleBufferInput input = bufferInput(positions, normals);
    CHECK(buildChecked(setup, pointLight(), input, lists.ids()) == Status::Ok);
    // Each output too small or missing, by name (validate), and as a Status (build).
    const char* names[] = {"counts", "offsets", "list_positions", "list_ids", "sample_slots", "sample_texels", "header",
                           "frustum"};
    for (int which = 0; which < 8; ++which) {
        CAPTURE(names[which]);
        gl::Buffer small(8);
        penumbra::SampleListsBuffers out = lists.ids();
        penumbra::BufferRange* fields[] = {&out.counts,       &out.offsets,       &out.list_positions, &out.list_ids,
                                           &out.sample_slots, &out.sample_texels, &out.header,         &out.frustum};
        *fields[which] = range(small);
        CHECK_THROWS_WITH_AS(builder().validate(setup, input, out),
                             doctest::Contains((std::string(names[which]) + " range holds 8 bytes").c_str()),
                             penumbra::Error);
        CHECK(builder().build(setup, pointLight(), input, out) == Status::RangeTooSmall);
        *fields[which] = penumbra::BufferRange{};
        CHECK_THROWS_WITH_AS(builder().validate(setup, input, out),
                             doctest::Contains((std::string(names[which]) + " buffer 0 is not a buffer object").c_str()),
                             penumbra::Error);
        CHECK(builder().build(setup, pointLight(), input, out) == Status::RangeTooSmall);
        // A range past the end of its buffer.
        *fields[which] = penumbra::BufferRange{small.id(), 0, 4096};
        CHECK_THROWS_WITH_AS(builder().validate(setup, input, out), doctest::Contains("exceeds buffer"),
                             penumbra::Error);
    }
    gl::Buffer small(100);
    CHECK_THROWS_WITH_AS(builder().validate(setup, bufferInput(small, normals), lists.ids()),
                         doctest::Contains("input positions range holds 100 bytes"), penumbra::Error);
    CHECK(builder().build(setup, pointLight(), bufferInput(small, normals), lists.ids()) == Status::RangeTooSmall);
    CHECK_THROWS_WITH_AS(builder().validate(setup, penumbra::SampleBufferInput{range(positions), {}}, lists.ids()),
                         doctest::Contains("input normals"), penumbra::Error);
    // Misaligned ranges: a Status, no GL call.
    gl::Buffer big(size_t(setup.sample_count) * 16 + 4096);
    CHECK(builder().build(setup, pointLight(), penumbra::SampleBufferInput{{big.id(), 4, 16000}, range(normals)},
                          lists.ids()) == Status::Misaligned);
    // Without culling the normals are not needed.
    const SampleListsOptions no_cull{false, LightDepthRange::MinusOneToOne};
    CHECK_NOTHROW(builder().validate(setup, penumbra::SampleBufferInput{range(positions), {}}, lists.ids(), no_cull));
    CHECK(builder().build(setup, pointLight(), penumbra::SampleBufferInput{range(positions), {}}, lists.ids(), no_cull) ==
          Status::Ok);
    // Bad light numbers: setup throws naming them; the per-frame call returns InvalidArgument.
    SampleListsLight bad = pointLight();
    bad.light.w = 2.0f;
    CHECK_THROWS_WITH_AS(penumbra::sampleListsParams(setup, bad), doctest::Contains("light.w = 2"), penumbra::Error);
    CHECK(builder().build(setup, bad, input, lists.ids()) == Status::InvalidArgument);
    bad = pointLight();
    bad.view_projection[2][1] = std::numeric_limits<float>::quiet_NaN();
    CHECK(builder().build(setup, bad, input, lists.ids()) == Status::InvalidArgument);
    // A grid larger than reserved.
    const SampleListsSetup larger = penumbra::sampleListsSetup(4096, 4096, 1000);
    penumbra::SampleListBuilder fresh;
    CHECK(fresh.build(setup, pointLight(), input, lists.ids()) == Status::NotReserved);
    fresh.reserve(setup);
    CHECK(fresh.build(larger, pointLight(), input, lists.ids()) == Status::NotReserved);
    // Depth input: size and texture checks.
    penumbra::SampleListsView view;
    view.width = 40;
    view.height = 25;
    gl::Texture depth(GL_TEXTURE_2D), normal(GL_TEXTURE_2D), cube(GL_TEXTURE_CUBE_MAP);
    glTextureStorage2D(depth.id(), 1, GL_DEPTH_COMPONENT32F, 40, 24);
    glTextureStorage2D(normal.id(), 1, GL_RGBA32F, 40, 25);
    glTextureStorage2D(cube.id(), 1, GL_RGBA8, 64, 64);
    CHECK_THROWS_WITH_AS(builder().validate(setup, penumbra::SampleDepthInput{depth.id(), normal.id(), view}, lists.ids()),
                         doctest::Contains("depth texture"), penumbra::Error);
    gl::Texture depth_ok(GL_TEXTURE_2D);
    glTextureStorage2D(depth_ok.id(), 1, GL_DEPTH_COMPONENT32F, 40, 25);
    CHECK(buildChecked(setup, pointLight(), penumbra::SampleDepthInput{depth_ok.id(), normal.id(), view}, lists.ids()) ==
          Status::Ok);
    CHECK_THROWS_WITH_AS(builder().validate(setup, penumbra::SampleDepthInput{depth_ok.id(), cube.id(), view}, lists.ids()),
                         doctest::Contains("normal texture"), penumbra::Error);
    // The builder reads through its own sampler object (compare mode off): a depth texture set up
    // for shadow lookups still works.
    glTextureParameteri(depth_ok.id(), GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    CHECK(buildChecked(setup, pointLight(), penumbra::SampleDepthInput{depth_ok.id(), normal.id(), view}, lists.ids()) ==
          Status::Ok);
    view.width = 41;
    CHECK_THROWS_WITH_AS(penumbra::sampleListsParams(setup, pointLight(), {}, &view), doctest::Contains("view 41 x 25"),
                         penumbra::Error);
    CHECK(builder().build(setup, pointLight(), penumbra::SampleDepthInput{depth_ok.id(), normal.id(), view}, lists.ids()) ==
          Status::InvalidArgument);
    gl::checkErrors("bad input");
}

TEST_CASE("§4.3 light-frustum fit: GPU equals CPU, every accepted sample stays inside, the box is tight") {
    context();
    const uint32_t seed = testSeed(5);
    std::mt19937 rng(seed);
    for (int kind = 0; kind < 2; ++kind) {
        CAPTURE(kind);
        const SampleListsLight light = kind == 0 ? pointLight() : directionalLight();
        // Samples in a small region, so the fit really crops.
        std::uniform_real_distribution<float> x(-0.6f, 0.4f), y(0.0f, 0.7f), z(-0.3f, 0.5f);
        const size_t n = 50000;
        Samples s;
        for (size_t i = 0; i < n; ++i) {
            s.positions.emplace_back(x(rng), y(rng), z(rng), 1.0f);
            s.normals.emplace_back(glm::normalize(glm::vec3(light.light.w == 0 ? glm::vec3(light.light)
                                                                                : glm::vec3(light.light) - glm::vec3(s.positions.back()))),
                                   0.0f);
            if (i % 97 == 0) s.positions.back().x = kNaN;
        }
        const SampleListsSetup setup = penumbra::sampleListsSetup(128, 128, n);
        const SampleListsOptions options;
        auto positions = gl::Buffer::fromVector(s.positions);
        auto normals = gl::Buffer::fromVector(s.normals);
        const penumbra::SampleBufferInput input = bufferInput(positions, normals);
        GpuLists fit_lists(setup);
        fit_lists.poison();
        const penumbra::LightFrustumFit gpu = gpuFit(setup, light, input, fit_lists, options);
        const penumbra::LightFrustumFit cpu =
            penumbra::fitLightFrustumCpu(setup, light, s.positions.data(), s.normals.data(), options);
        REQUIRE(gpu.valid);
        REQUIRE(cpu.valid);
        PENUMBRA_CHECK_BITWISE("light-frustum fit: GPU keys == CPU twin", std::memcmp(&gpu.keys.fit_min_u, &cpu.keys.fit_min_u, 8 * 4) == 0);
        // The frustum the GPU resolved for itself equals the twin's, every word (llvmpipe rounds
        // fp64 correctly; see fit_resolve.comp.glsl for other drivers).
        PENUMBRA_CHECK_BITWISE("light-frustum fit: GPU frustum == CPU twin", std::memcmp(&gpu.frustum, &cpu.frustum, sizeof(penumbra::SampleListsFrustum)) == 0);
        PENUMBRA_CHECK_BITWISE("light-frustum fit: GPU view-projection == CPU twin", std::memcmp(&gpu.view_projection, &cpu.view_projection, sizeof(glm::mat4)) == 0);
        PENUMBRA_CHECK_BITWISE("light-frustum fit: GPU crop == CPU twin", std::memcmp(&gpu.crop, &cpu.crop, sizeof(glm::mat4)) == 0);
        PENUMBRA_CHECK_BITWISE("light-frustum fit: GPU far distance == CPU twin", gpu.far_distance == cpu.far_distance);
        {
            // The lists of that same build used the GPU's fitted frustum, with no read-back between.
            SampleListsLight fitted_by_gpu = light;
            fitted_by_gpu.view_projection = gpu.view_projection;
            PENUMBRA_CHECK_BITWISE("sample lists GPU == CPU twin", penumbra::sampleListsDifference(penumbra::downloadSampleLists(setup, fit_lists.ids()),
                                                  cpuBuild(setup, fitted_by_gpu, s, options)) == "");
        }
        // Closed form: the box and the farthest distance from the samples in double precision.
        const SampleListsCpu original = cpuBuild(setup, light, s, options);
        CHECK(cpu.samples == original.header.accepted);
        const glm::dmat4 t_matrix(penumbra::lightTextureMatrix(light.view_projection, options.depth_range));
        double umin = 1, umax = 0, farthest = -1e30;
        for (uint32_t id = 0; id < n; ++id) {
            if (original.sample_slots[id] == penumbra::kSampleListsNoSlot) continue;
            const glm::dvec3 p(s.positions[id]);
            const glm::dvec4 t = t_matrix * glm::dvec4(p, 1.0);
            umin = std::min(umin, t.x / t.w);
            umax = std::max(umax, t.x / t.w);
            farthest = std::max(farthest, light.light.w == 0 ? -glm::dot(p, glm::normalize(glm::dvec3(light.light)))
                                                             : glm::length(p - glm::dvec3(light.light)));
        }
        CHECK(cpu.min_uv.x == doctest::Approx(umin).epsilon(1e-5));
        CHECK(cpu.max_uv.x == doctest::Approx(umax).epsilon(1e-5));
        CHECK(cpu.far_distance == doctest::Approx(farthest).epsilon(1e-5));
        CHECK(cpu.max_uv.x - cpu.min_uv.x < 0.6f);  // the samples cover part of the frustum only

        // Rebuild with the fitted frustum: the same samples are accepted (none outside or beyond
        // far), on the GPU and the CPU, and they fill the fitted grid up to the margin.
        SampleListsLight fitted = light;
        fitted.view_projection = gpu.view_projection;
        const SampleListsCpu cpu_fitted = cpuBuild(setup, fitted, s, options);
        const SampleListsCpu gpu_fitted = gpuBuild(setup, fitted, s, options);
        PENUMBRA_CHECK_BITWISE("sample lists GPU == CPU twin", penumbra::sampleListsDifference(gpu_fitted, cpu_fitted) == "");
        CHECK(cpu_fitted.header.accepted == original.header.accepted);
        size_t lost = 0;
        for (uint32_t id = 0; id < n; ++id) {
            lost += (original.sample_slots[id] == penumbra::kSampleListsNoSlot) !=
                    (cpu_fitted.sample_slots[id] == penumbra::kSampleListsNoSlot);
        }
        CHECK(lost == 0);
        const penumbra::LightFrustumFit refit =
            penumbra::fitLightFrustumCpu(setup, fitted, s.positions.data(), s.normals.data(), options);
        CHECK(refit.min_uv.x > 0.0f);
        CHECK(refit.min_uv.x < 0.01f);
        CHECK(refit.max_uv.x < 1.0f);
        CHECK(refit.max_uv.x > 0.99f);
        CHECK(refit.min_uv.y < 0.01f);
        CHECK(refit.max_uv.y > 0.99f);
        CHECK(refit.max_depth < 1.0f);
        CHECK(refit.max_depth > 0.99f);
        // The fitted frustum spreads the samples over more lists (§4.3: shorter lists).
        CHECK(penumbra::sampleListStatisticsCpu(cpu_fitted).occupied_lists >
              penumbra::sampleListStatisticsCpu(original).occupied_lists);
    }
    // Depth input and a single-point box (degenerate): GPU == CPU and the point stays inside.
    penumbra::SampleListsView view;
    view.width = 33;
    view.height = 17;
    view.inverse_view_projection = glm::inverse(glm::perspective(glm::radians(50.0f), 2.0f, 0.5f, 12.0f) *
                                                glm::lookAt(glm::vec3(0, 3, 5), glm::vec3(0), glm::vec3(0, 1, 0)));
    std::vector<float> depth(33 * 17, 1.0f);
    depth[17 * 5 + 3] = 0.97f;
    std::vector<glm::vec4> normals(depth.size(), glm::vec4(0, 1, 0, 0));
    gl::Texture depth_texture(GL_TEXTURE_2D), normal_texture(GL_TEXTURE_2D);
    glTextureStorage2D(depth_texture.id(), 1, GL_DEPTH_COMPONENT32F, 33, 17);
    glTextureSubImage2D(depth_texture.id(), 0, 0, 0, 33, 17, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
    glTextureStorage2D(normal_texture.id(), 1, GL_RGBA32F, 33, 17);
    glTextureSubImage2D(normal_texture.id(), 0, 0, 0, 33, 17, GL_RGBA, GL_FLOAT, normals.data());
    const SampleListsSetup setup = penumbra::sampleListsSetup(64, 64, depth.size());
    GpuLists fit_lists(setup);
    const penumbra::SampleDepthInput input{depth_texture.id(), normal_texture.id(), view};
    const auto gpu = gpuFit(setup, pointLight(), input, fit_lists);
    const auto cpu = penumbra::fitLightFrustumCpu(setup, pointLight(), view, depth.data(), normals.data());
    REQUIRE(cpu.valid);
    CHECK(cpu.samples == 1);
    PENUMBRA_CHECK_BITWISE("light-frustum fit (depth input): GPU view-projection == CPU twin", std::memcmp(&gpu.view_projection, &cpu.view_projection, sizeof(glm::mat4)) == 0);
    SampleListsLight fitted = pointLight();
    fitted.view_projection = cpu.view_projection;
    const SampleListsCpu lists = penumbra::buildSampleListsCpu(setup, fitted, view, depth.data(), normals.data());
    CHECK(lists.header.accepted == 1);
    // Centred in the fitted grid: u' = 0.5 up to rounding, so texel 31 or 32 on each axis.
    const uint32_t texel = lists.sample_texels[17 * 5 + 3];
    CHECK((texel % 64 == 31 || texel % 64 == 32));
    CHECK((texel / 64 == 31 || texel / 64 == 32));
    gl::checkErrors("fit");
}

TEST_CASE("Fig. 9 statistics: GPU equals CPU equals the closed form") {
    context();
    const uint32_t seed = testSeed(6);
    std::mt19937 rng(seed);
    for (auto grid : {std::pair<uint32_t, uint32_t>{1, 1}, {255, 1}, {256, 2}, {129, 257}}) {
        CAPTURE(grid.first);
        CAPTURE(grid.second);
        const SampleListsSetup setup = penumbra::sampleListsSetup(grid.first, grid.second, 40000);
        const Samples samples = randomSamples(rng, setup.sample_count);
        GpuLists lists(setup);
        const SampleListsCpu gpu = gpuBuild(setup, pointLight(), samples, {}, &lists);
        const SampleListsCpu cpu = cpuBuild(setup, pointLight(), samples, {});
        PENUMBRA_CHECK_BITWISE("sample lists GPU == CPU twin", penumbra::sampleListsDifference(gpu, cpu) == "");
        // Poison the statistics words: the pass must initialise them itself.
        const uint32_t poison = kPoison;
        glClearNamedBufferSubData(lists.header.id(), GL_R32UI, 4 * PENUMBRA_SAMPLE_LISTS_HEADER_STATISTICS_WORD, 16,
                                  GL_RED_INTEGER, GL_UNSIGNED_INT, &poison);
        const penumbra::SampleListStatistics on_gpu = gpuStatistics(setup, lists);
        const penumbra::SampleListStatistics on_cpu = penumbra::sampleListStatisticsCpu(gpu);  // of the GPU's lists: any driver
        CHECK(on_gpu == on_cpu);
        // Closed form from the downloaded counts and per-sample codes.
        uint32_t occupied = 0, longest = 0;
        uint64_t listed = 0;
        for (uint32_t c : gpu.counts) {
            occupied += c != 0;
            longest = std::max(longest, c);
            listed += c;
        }
        std::array<uint32_t, penumbra::kSampleListsReasonCount> rejected{};
        uint32_t accepted = 0;
        for (uint32_t c : gpu.sample_texels) {
            if (c < penumbra::kSampleListsRejected) ++accepted;
            else ++rejected[c - penumbra::kSampleListsRejected];
        }
        CHECK(on_gpu.lists == setup.lists);
        CHECK(on_gpu.occupied_lists == occupied);
        CHECK(on_gpu.max_list_length == longest);
        CHECK(on_gpu.listed_samples == listed);
        CHECK(on_gpu.accepted == accepted);
        CHECK(on_gpu.rejected == rejected);
        CHECK(on_gpu.rejectedTotal() + on_gpu.accepted == setup.sample_count);
        CHECK(on_gpu.occupancy() == double(occupied) / setup.lists);
        CHECK(on_gpu.averageOccupiedLength() == double(listed) / occupied);
        CHECK(on_gpu.averageLength() == double(listed) / setup.lists);
        for (uint32_t r = 0; r < penumbra::kSampleListsReasonCount; ++r) {
            CAPTURE(penumbra::sampleRejectionName(SampleRejection(r)));
            CHECK(rejected[r] > 0);  // every reason occurs in randomSamples (Depth via the far plane)
        }
    }
    gl::checkErrors("statistics");
}

TEST_CASE("stress: large random builds equal the CPU twin" * doctest::test_suite("stress")) {
    context();
    const uint32_t seed = testSeed(7);
    std::mt19937 rng(seed);
    for (auto grid : {std::pair<uint32_t, uint32_t>{1024, 1024}, {4096, 4096}, {16384, 3}}) {
        for (const SampleListsLight& light : {pointLight(), directionalLight()}) {
            const SampleListsSetup setup = penumbra::sampleListsSetup(grid.first, grid.second, 65535u * 256u + 77u);
            const Samples samples = randomSamples(rng, setup.sample_count);
            const SampleListsCpu cpu = cpuBuild(setup, light, samples, {});
            const SampleListsCpu gpu = gpuBuild(setup, light, samples, {});
            PENUMBRA_CHECK_BITWISE("sample lists GPU == CPU twin", penumbra::sampleListsDifference(gpu, cpu) == "");
            checkStructure(setup, gpu, samples.positions.data(), nullptr);
        }
    }
}
TEST_CASE("a fresh builder needs reserve(); a moved builder builds the same structure") {
    context();
    std::mt19937 rng(testSeed(8));
    const SampleListsSetup setup = penumbra::sampleListsSetup(32, 32, 1024);
    const Samples samples = randomSamples(rng, setup.sample_count);
    auto positions = gl::Buffer::fromVector(samples.positions);
    auto normals = gl::Buffer::fromVector(samples.normals);
    GpuLists lists(setup);
    lists.poison();
    penumbra::SampleListBuilder b;
    CHECK(b.build(setup, pointLight(), bufferInput(positions, normals), lists.ids()) == Status::NotReserved);
    b.reserve(setup);
    penumbra::SampleListBuilder moved(std::move(b));
    CHECK(moved.build(setup, pointLight(), bufferInput(positions, normals), lists.ids()) == Status::Ok);
    const SampleListsCpu gpu = penumbra::downloadSampleLists(setup, lists.ids());
    PENUMBRA_CHECK_BITWISE("sample lists GPU == CPU twin", penumbra::sampleListsDifference(gpu, cpuBuild(setup, pointLight(), samples, {})) == "");
}

TEST_CASE("planSampleLists: pass order, grids, bindings, programs and constants without GL") {
    using K = penumbra::SampleListsStepKind;
    using R = penumbra::SampleListsResource;
    using penumbra::SampleListsBarrier;
    using penumbra::SampleListsKernel;
    const SampleListsLight light = pointLight();
    auto kinds = [](const penumbra::SampleListsPlan& plan) {
        std::string out;
        for (const penumbra::SampleListsStep& s : plan.steps) {
            out += penumbra::sampleListsStepKindName(s.kind);
            if (s.kind == K::Upload || s.kind == K::Clear) {
                out += std::string(":") + penumbra::sampleListsResourceName(s.resource);
            }
            if (s.kind == K::Dispatch) out += ":" + std::string(penumbra::sampleListsKernelKey(s.kernel)).substr(22);
            out += " ";
        }
        return out;
    };
    auto find = [](const penumbra::SampleListsPlan& plan,
                   SampleListsKernel kernel) -> const penumbra::SampleListsStep* {
        for (const penumbra::SampleListsStep& s : plan.steps) {
            if (s.kind == K::Dispatch && s.kernel == kernel) return &s;
        }
        return nullptr;
    };
    auto bound = [](const penumbra::SampleListsStep& s, R r) -> const penumbra::SampleListsBinding* {
        for (uint32_t i = 0; i < s.binding_count; ++i) {
            if (s.bindings[i].resource == r) return &s.bindings[i];
        }
        return nullptr;
    };

    // Everything on: fit, count, scan, scatter, statistics.
    for (size_t n : {size_t(1), size_t(255), size_t(256), size_t(257), size_t(65537)}) {
        CAPTURE(n);
        const SampleListsSetup setup = penumbra::sampleListsSetup(300, 200, n);
        penumbra::SampleListsBuild build;
        build.fit_frustum = true;
        build.statistics = true;
        const penumbra::SampleListsPlan plan =
            penumbra::planSampleLists(setup, light, {}, build, penumbra::SampleListsInputKind::Buffer);
        CHECK(kinds(plan) ==
              "upload:params clear:counts clear:header clear:header clear:header dispatch:fit.comp.glsl barrier "
              "dispatch:fit_resolve.comp.glsl barrier dispatch:count.comp.glsl scan barrier "
              "dispatch:scatter.comp.glsl barrier clear:header dispatch:statistics.comp.glsl barrier ");
        const uint64_t groups = (n + 255) / 256;
        for (SampleListsKernel k : {SampleListsKernel::Fit, SampleListsKernel::Count, SampleListsKernel::Scatter}) {
            const penumbra::SampleListsStep* s = find(plan, k);
            REQUIRE(s);
            CHECK(s->grid.groups == groups);
            CHECK(uint64_t(s->grid.x) * s->grid.y >= groups);
            CHECK(s->grid.x == setup.sample_groups.x);
            CHECK(s->grid.y == setup.sample_groups.y);
            REQUIRE(bound(*s, R::Params));
            CHECK(bound(*s, R::Params)->kind == penumbra::SampleListsBindingKind::UniformBuffer);
            CHECK(bound(*s, R::Positions)->bytes == n * 16);
            CHECK(bound(*s, R::Normals)->point == PENUMBRA_SAMPLE_LISTS_BINDING_NORMALS);
        }
        CHECK(find(plan, SampleListsKernel::FitResolve)->grid.x == 1);
        CHECK(find(plan, SampleListsKernel::FitResolve)->grid.y == 1);
        CHECK(bound(*find(plan, SampleListsKernel::FitResolve), R::Frustum)->point ==
              PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM_OUT);
        CHECK(bound(*find(plan, SampleListsKernel::Count), R::Frustum)->kind ==
              penumbra::SampleListsBindingKind::UniformBuffer);
        CHECK(bound(*find(plan, SampleListsKernel::Count), R::Counts)->bytes == setup.counts_bytes);
        CHECK(bound(*find(plan, SampleListsKernel::Scatter), R::Counts) == nullptr);
        CHECK(find(plan, SampleListsKernel::Statistics)->grid.groups == (60000 + 255) / 256);
        CHECK(plan.steps[6].barriers == SampleListsBarrier::Storage);
        CHECK(plan.steps[8].barriers == (SampleListsBarrier::Storage | SampleListsBarrier::Uniform));
        CHECK(static_cast<uint32_t>(plan.steps[plan.steps.size() - 1].barriers) == 0x2244u);
        // The scan step: W * H counts into offsets, the embedded plan planScan's own.
        CHECK(plan.steps[10].kind == K::Scan);
        CHECK(plan.steps[10].resource == R::Counts);
        CHECK(plan.steps[10].output == R::Offsets);
        CHECK(plan.steps[10].elements == 60000);
        CHECK(plan.scan.n == 60000);
        CHECK(plan.scan.dispatch_list.size() == penumbra::planScan(60000).dispatch_list.size());
        CHECK(plan.scan.dispatch_list.size() > 1);  // reduce, top, scan
        // Constants: the blocks the executor uploads.
        const penumbra::SampleListsParams params = penumbra::sampleListsParams(setup, light, {}, nullptr, build.fit);
        CHECK(std::memcmp(&plan.params, &params, sizeof params) == 0);
        const penumbra::SampleListsFrustum frustum = penumbra::sampleListsFrustum(params);
        CHECK(std::memcmp(&plan.frustum, &frustum, sizeof frustum) == 0);
        // Programs once each, in first-use order; the input permutation only where it exists.
        REQUIRE(plan.programs.size() == 5);
        CHECK(plan.programs[0].kernel == SampleListsKernel::Fit);
        CHECK(plan.programs[4].kernel == SampleListsKernel::Statistics);
        for (const penumbra::SampleListsProgram& p : plan.programs) {
            bool has_input = false;
            for (const penumbra::ShaderDefine& d : p.defines) has_input |= d.name == "PENUMBRA_SAMPLE_LISTS_INPUT";
            CHECK(has_input == penumbra::sampleListsKernelPerInput(p.kernel));
        }
    }

    // Nothing optional, no samples: no dispatch at all, the host uploads the frustum.
    {
        const SampleListsSetup setup = penumbra::sampleListsSetup(13, 7, 0);
        const penumbra::SampleListsPlan plan =
            penumbra::planSampleLists(setup, light, {}, {}, penumbra::SampleListsInputKind::Buffer);
        CHECK(kinds(plan) == "upload:params clear:counts clear:header upload:frustum scan barrier barrier ");
        CHECK(plan.programs.empty());
        CHECK(plan.steps[1].words == 91);
        CHECK(plan.steps[3].bytes == sizeof(penumbra::SampleListsFrustum));
    }

    // Depth input, culling off, custom binding points: textures by unit, no normals, defines follow.
    {
        penumbra::SampleListsView view;
        view.width = 16;
        view.height = 16;
        const SampleListsSetup setup = penumbra::sampleListsSetup(8, 8, 256);
        SampleListsOptions options;
        options.cull_back_facing = false;
        penumbra::SampleListsPlanOptions po;
        po.bindings.counts = 6;
        po.bindings.depth_unit = 5;
        const penumbra::SampleListsPlan plan = penumbra::planSampleLists(
            setup, light, options, {}, penumbra::SampleListsInputKind::Depth, &view, po);
        CHECK(kinds(plan) == "upload:params clear:counts clear:header upload:frustum dispatch:count.comp.glsl scan "
                             "barrier dispatch:scatter.comp.glsl barrier ");
        const penumbra::SampleListsStep* count = find(plan, SampleListsKernel::Count);
        REQUIRE(count);
        CHECK(bound(*count, R::DepthTexture)->point == 5);
        CHECK(bound(*count, R::DepthTexture)->kind == penumbra::SampleListsBindingKind::Texture);
        CHECK(bound(*count, R::NormalTexture) == nullptr);
        CHECK(bound(*count, R::Positions) == nullptr);
        CHECK(bound(*count, R::Counts)->point == 6);
        CHECK(plan.params.view.x == 16);
        const penumbra::SampleListsProgram* program = plan.program(SampleListsKernel::Count);
        REQUIRE(program);
        CHECK(std::string(program->key) == "penumbra/sample_lists/count.comp.glsl");
        int matched = 0;
        for (const penumbra::ShaderDefine& d : program->defines) {
            matched += d.name == "PENUMBRA_SAMPLE_LISTS_INPUT" && d.value == "1";
            matched += d.name == "PENUMBRA_SAMPLE_LISTS_BINDING_COUNTS" && d.value == "6";
            matched += d.name == "PENUMBRA_SAMPLE_LISTS_UNIT_DEPTH" && d.value == "5";
        }
        CHECK(matched == 3);
        CHECK(plan.program(SampleListsKernel::Fit) == nullptr);
        // The view belongs to the depth input, and only to it.
        CHECK_THROWS_WITH_AS(
            penumbra::planSampleLists(setup, light, options, {}, penumbra::SampleListsInputKind::Depth),
            doctest::Contains("needs its view"), penumbra::Error);
        CHECK_THROWS_WITH_AS(
            penumbra::planSampleLists(setup, light, options, {}, penumbra::SampleListsInputKind::Buffer, &view),
            doctest::Contains("only for the depth input"), penumbra::Error);
        SampleListsLight bad = light;
        bad.light.w = 0.5f;
        CHECK_THROWS_WITH_AS(penumbra::planSampleLists(setup, bad, options, {}, penumbra::SampleListsInputKind::Buffer),
                             doctest::Contains("light.w = 0.5"), penumbra::Error);
    }
}

TEST_CASE("RHI-style replay: the plan recorded with raw GL calls equals the executor and the CPU twin") {
    context();
    const uint32_t seed = testSeed(9);
    std::mt19937 rng(seed);
    const std::pair<uint32_t, uint32_t> grids[] = {{64, 48}, {300, 200}, {1, 1}, {257, 129}};
    // Other binding points than the defaults: the plan's defines and bindings follow them. Each size
    // runs the four combinations of (fit or upload of the frustum) x (default or these points).
    penumbra::SampleListsBindingPoints moved;
    moved.params = 2;
    moved.frustum = 3;
    moved.positions = 7;
    moved.normals = 6;
    moved.counts = 5;
    moved.frustum_out = 5;
    moved.offsets = 4;
    moved.header = 4;
    moved.list_positions = 3;
    moved.list_ids = 2;
    moved.sample_slots = 1;
    moved.sample_texels = 0;
    moved.depth_unit = 3;
    moved.normal_unit = 2;
    int round = 0;
    uint64_t accepted = 0;
    // Buffer input.
    for (size_t n : {size_t(0), size_t(1), size_t(255), size_t(256), size_t(257), size_t(65537)}) {
        for (int config = 0; config < 4; ++config) {
            const auto grid = grids[(round++) % 4];
            CAPTURE(n);
            CAPTURE(config);
            CAPTURE(grid.first);
            CAPTURE(grid.second);
            const SampleListsLight light = round % 3 == 0 ? directionalLight() : pointLight();
            const SampleListsSetup setup = penumbra::sampleListsSetup(grid.first, grid.second, n);
            const Samples samples = randomSamples(rng, n);
            SampleListsOptions options;
            options.cull_back_facing = round % 4 != 1;
            penumbra::SampleListsBuild build;
            build.fit_frustum = build.statistics = (config & 1) != 0;
            auto positions = gl::Buffer::fromVector(samples.positions);
            auto normals = gl::Buffer::fromVector(samples.normals);
            const penumbra::SampleBufferInput input = bufferInput(positions, normals);
            accepted += checkReplay(setup, light, options, build, (config & 2) != 0 ? &moved : nullptr, &input, nullptr,
                                    [&](const SampleListsLight& l) { return cpuBuild(setup, l, samples, options); });
        }
    }
    // Depth input: 1, 255, 256, 257 and 65 792 samples.
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f), d01(0.0f, 1.0f);
    for (auto size : {std::pair<uint32_t, uint32_t>{1, 1}, {255, 1}, {16, 16}, {257, 1}, {256, 257}}) {
        for (int config = 0; config < 4; ++config) {
            const auto grid = grids[(round++) % 4];
            const uint32_t vw = size.first, vh = size.second;
            CAPTURE(vw);
            CAPTURE(vh);
            CAPTURE(config);
            penumbra::SampleListsView view;
            view.width = vw;
            view.height = vh;
            view.depth_zero_to_one = round % 2;
            const glm::mat4 projection = view.depth_zero_to_one
                                             ? glm::perspectiveRH_ZO(glm::radians(50.0f), 1.0f, 0.5f, 12.0f)
                                             : glm::perspective(glm::radians(50.0f), 1.0f, 0.5f, 12.0f);
            const glm::mat4 camera =
                projection * glm::lookAt(glm::vec3(0.0f, 3.0f, 5.0f), glm::vec3(0.0f), glm::vec3(0, 1, 0));
            view.inverse_view_projection = glm::inverse(camera);
            std::vector<float> depth(size_t(vw) * vh);
            std::vector<glm::vec4> normals(depth.size());
            for (size_t i = 0; i < depth.size(); ++i) {
                const float r = d01(rng);
                depth[i] = r < 0.1f ? 1.0f : std::pow(d01(rng), 0.2f);
                normals[i] = glm::vec4(glm::normalize(glm::vec3(unit(rng), unit(rng) + 1.5f, unit(rng))), 0.0f);
            }
            gl::Texture depth_texture(GL_TEXTURE_2D), normal_texture(GL_TEXTURE_2D);
            glTextureStorage2D(depth_texture.id(), 1, GL_DEPTH_COMPONENT32F, GLsizei(vw), GLsizei(vh));
            glTextureSubImage2D(depth_texture.id(), 0, 0, 0, GLsizei(vw), GLsizei(vh), GL_DEPTH_COMPONENT, GL_FLOAT,
                                depth.data());
            glTextureStorage2D(normal_texture.id(), 1, GL_RGBA32F, GLsizei(vw), GLsizei(vh));
            glTextureSubImage2D(normal_texture.id(), 0, 0, 0, GLsizei(vw), GLsizei(vh), GL_RGBA, GL_FLOAT,
                                normals.data());
            const SampleListsLight light = round % 3 == 0 ? directionalLight() : pointLight();
            SampleListsOptions options;
            options.cull_back_facing = round % 4 != 2;
            penumbra::SampleListsBuild build;
            build.fit_frustum = build.statistics = (config & 1) != 0;
            const SampleListsSetup setup = penumbra::sampleListsSetup(grid.first, grid.second, depth.size());
            const penumbra::SampleDepthInput input{depth_texture.id(), normal_texture.id(), view};
            accepted += checkReplay(setup, light, options, build, (config & 2) != 0 ? &moved : nullptr, nullptr, &input,
                                    [&](const SampleListsLight& l) {
                                        return penumbra::buildSampleListsCpu(setup, l, view, depth.data(),
                                                                             normals.data(), options);
                                    });
        }
    }
    MESSAGE(round, " builds replayed, ", accepted, " samples accepted");
    CHECK(accepted > 10000);
}
