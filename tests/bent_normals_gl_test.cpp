// bent_normals.glsl on the GPU: bent_normals.comp.glsl's l_bend per vertex and penumbraBentShade /
// penumbraBentDirect equal the CPU twins bit for bit (bitwise tier, support/gl_test_support.hpp:
// llvmpipe rounds float correctly); on any driver they agree within 1e-4 (portable tier: GLSL's
// division and sqrt are within 3 ulp, FMA contraction is allowed, and these are short chains of
// values of magnitude <= a few units), the back-face guarantee does not change. Hard-edged meshes
// (cube, cone, tetrahedron with shared vertices) run through the same shader with their crease
// copies: lit corners get their own face's dot(l, n_F), never a back face's (issue 41 item 6).
#include <penumbra/bent_normals.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/shader.hpp>
#include <penumbra/scene/scene.hpp>

#include "support/gl_test_support.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace {

uint32_t bits(float f) {
    uint32_t b;
    std::memcpy(&b, &f, 4);
    return b;
}

/// bent_normals.comp.glsl's l_bend for every bent vertex (positions per input vertex, via source).
std::vector<float> gpuBentLight(const penumbra::gl::Program& program, const penumbra::BentNormalMesh& bent,
                                const std::vector<glm::vec3>& mesh_positions, const glm::vec3& light, float radius) {
    std::vector<glm::vec4> positions;
    for (const glm::vec3& p : mesh_positions) positions.emplace_back(p, 1.0f);
    penumbra::gl::Buffer position_buffer = penumbra::gl::Buffer::fromVector(positions);
    penumbra::gl::Buffer source = penumbra::gl::Buffer::fromVector(bent.source);
    penumbra::gl::Buffer offsets = penumbra::gl::Buffer::fromVector(bent.offsets);
    penumbra::gl::Buffer faces = penumbra::gl::Buffer::fromVector(bent.faces);
    penumbra::gl::Buffer normals = penumbra::gl::Buffer::fromVector(bent.face_normals);
    std::vector<float> poison(bent.bentVertexCount(), std::nanf(""));
    penumbra::gl::Buffer output = penumbra::gl::Buffer::fromVector(poison);
    penumbra::shared::PenumbraBentParams params{};
    params.light = glm::vec4(light, radius);
    params.vertex_count = bent.bentVertexCount();
    penumbra::gl::Buffer params_buffer(sizeof params, &params);
    glUseProgram(program.id());
    glBindBufferBase(GL_UNIFORM_BUFFER, PENUMBRA_BENT_BINDING_PARAMS, params_buffer.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_BENT_BINDING_POSITIONS, position_buffer.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_BENT_BINDING_SOURCE, source.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_BENT_BINDING_OFFSETS, offsets.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_BENT_BINDING_FACES, faces.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_BENT_BINDING_FACE_NORMALS, normals.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_BENT_BINDING_OUTPUT, output.id());
    glDispatchCompute((bent.bentVertexCount() + PENUMBRA_BENT_GROUP_SIZE - 1) / PENUMBRA_BENT_GROUP_SIZE, 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    return output.download<float>();
}

/// A convex solid with one vertex per corner position (shared by every face there), triangles
/// turned to face away from the centroid: cube, 5-sided cone, tetrahedron.
struct Solid {
    std::string name;
    std::vector<glm::vec3> positions;
    std::vector<uint32_t> indices;
    void outward(uint32_t a, uint32_t b, uint32_t c) {
        glm::dvec3 centre(0.0);
        for (const glm::vec3& p : positions) centre += glm::dvec3(p) / double(positions.size());
        const glm::dvec3 pa(positions[a]), pb(positions[b]), pc(positions[c]);
        const bool inward = glm::dot(glm::cross(pb - pa, pc - pa), pa - centre) < 0.0;
        indices.insert(indices.end(), {a, inward ? c : b, inward ? b : c});
    }
};

std::vector<Solid> solids() {
    Solid cube{"cube", {}, {}}, cone{"cone", {{0.0f, 2.0f, 0.0f}}, {}};
    Solid tetrahedron{"tetrahedron", {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}}, {}};
    for (uint32_t i = 0; i < 8; ++i) cube.positions.emplace_back(i & 1 ? 1.0f : -1.0f, i & 2 ? 1.0f : -1.0f, i & 4 ? 1.0f : -1.0f);
    for (uint32_t axis = 0; axis < 3; ++axis)
        for (uint32_t side = 0; side < 2; ++side) {
            const uint32_t i = 1u << ((axis + 1) % 3), j = 1u << ((axis + 2) % 3), base = side << axis;
            cube.outward(base, base | i, base | i | j);
            cube.outward(base, base | i | j, base | j);
        }
    for (uint32_t k = 0; k < 5; ++k) {
        const double a = 2.0 * 3.14159265358979323846 * k / 5;
        cone.positions.emplace_back(float(std::cos(a)), -1.0f, float(std::sin(a)));
    }
    for (uint32_t k = 0; k < 5; ++k) cone.outward(0, 1 + k, 1 + (k + 1) % 5);
    for (uint32_t k = 1; k + 1 < 5; ++k) cone.outward(1, 1 + k, 2 + k);
    tetrahedron.outward(0, 1, 2), tetrahedron.outward(0, 1, 3), tetrahedron.outward(0, 2, 3), tetrahedron.outward(1, 2, 3);
    return {cube, cone, tetrahedron};
}

}  // namespace

TEST_CASE("GPU: bent_normals.comp.glsl l_bend == bentLight bit for bit (torus knot, point and sphere light)") {
    penumbra::test::context();
    const penumbra::gl::Program program = penumbra::gl::buildComputeProgram("penumbra/bent_normals/bent_normals.comp.glsl");
    const penumbra::scene::Scene knot = penumbra::scene::torusKnot(64, false);
    const penumbra::scene::Mesh& mesh = knot.meshes[0];
    const penumbra::BentNormalMesh bent =
        penumbra::bentNormalMesh(mesh.positions.data(), mesh.positions.size(), mesh.indices.data(), mesh.indices.size());
    for (const float radius : {0.0f, knot.light.radius, 2.0f}) {
        CAPTURE(radius);
        const std::vector<float> gpu = gpuBentLight(program, bent, mesh.positions, knot.light.position, radius);
        size_t mismatched = 0, negative = 0;
        double max_difference = 0.0;
        for (uint32_t v = 0; v < bent.bentVertexCount(); ++v) {
            const float cpu = penumbra::bentLight(bent, v, mesh.positions[bent.source[v]], knot.light.position, radius);
            mismatched += bits(cpu) != bits(gpu[v]);
            negative += cpu < 0.0f;
            const double d = std::abs(double(gpu[v]) - cpu);
            max_difference = std::max(max_difference, std::isfinite(d) ? d : 1e30);
        }
        MESSAGE("radius " << radius << ": " << bent.bentVertexCount() << " vertices, " << negative << " with l_bend < 0, "
                          << mismatched << " GPU != CPU, largest difference " << max_difference);
        PENUMBRA_CHECK_BITWISE("bent normals l_bend GPU == CPU twin bit for bit", mismatched == 0);
        CHECK(max_difference <= 1e-4);
        CHECK(negative > 0);
    }
}

TEST_CASE("GPU: bent_normals.comp.glsl on hard-edged meshes: crease copies, lit corners see their own face (cube, cone, tetrahedron)") {
    penumbra::test::context();
    const penumbra::gl::Program program = penumbra::gl::buildComputeProgram("penumbra/bent_normals/bent_normals.comp.glsl");
    const glm::vec3 light(1e5f * glm::normalize(glm::vec3(1.0f, 2.0f, 3.0f)));  // three cube faces lit
    for (const Solid& solid : solids()) {
        CAPTURE(solid.name);
        const penumbra::BentNormalMesh bent = penumbra::bentNormalMesh(solid.positions.data(), solid.positions.size(),
                                                                       solid.indices.data(), solid.indices.size());
        CHECK(bent.crease_copies > 0);
        const std::vector<float> gpu = gpuBentLight(program, bent, solid.positions, light, 0.0f);
        size_t mismatched = 0, lit_corners = 0, dark_lit_corners = 0, back_corners = 0, lit_back_corners = 0;
        double max_difference = 0.0;
        for (uint32_t v = 0; v < bent.bentVertexCount(); ++v) {
            const float cpu = penumbra::bentLight(bent, v, solid.positions[bent.source[v]], light);
            mismatched += bits(cpu) != bits(gpu[v]);
            const double d = std::abs(double(gpu[v]) - cpu);
            max_difference = std::max(max_difference, std::isfinite(d) ? d : 1e30);
        }
        // Each corner's value against its own face's dot(l, n_F) at that vertex (within float
        // rounding: a flat face's triangles may differ in the last bits of their normals).
        for (size_t c = 0; c < solid.indices.size(); ++c) {
            const glm::vec3 n(bent.face_normals[c / 3]), p = solid.positions[solid.indices[c]];
            const float own = glm::dot(glm::normalize(light - p), n), value = gpu[bent.indices[c]];
            if (own > 0.0f) {
                ++lit_corners;
                dark_lit_corners += !(std::abs(value - own) <= 1e-6f);
            } else if (own < 0.0f) {
                ++back_corners;
                lit_back_corners += !(value < 0.0f);
            }
        }
        MESSAGE(solid.name << ": " << bent.bentVertexCount() << " bent vertices, " << mismatched << " GPU != CPU (largest "
                           << max_difference << "); " << lit_corners << " lit corners, " << dark_lit_corners
                           << " not their face's dot; " << back_corners << " back corners, " << lit_back_corners << " not < 0");
        PENUMBRA_CHECK_BITWISE("bent normals l_bend GPU == CPU twin bit for bit (crease copies)", mismatched == 0);
        CHECK(max_difference <= 1e-4);
        CHECK(lit_corners > 0);
        CHECK(back_corners > 0);
        CHECK(dark_lit_corners == 0);
        CHECK(lit_back_corners == 0);
    }
}

TEST_CASE("GPU: penumbraBentShade / penumbraBentDirect == bentShade / bentDirect bit for bit (up to the sign of 0)") {
    penumbra::test::context();
    penumbra::ShaderLibrary lib = penumbra::ShaderLibrary::embedded();
    lib.addDirectory(penumbra::test::testShaderDir());
    const penumbra::gl::Program program = penumbra::gl::buildComputeProgram("bent_normals/shade_test.comp.glsl", {}, lib);
    std::mt19937 rng(penumbra::test::testSeed());
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    std::vector<glm::vec4> inputs;
    for (int i = 0; i < 4096; ++i) inputs.emplace_back(unit(rng), unit(rng), i % 4 == 0 ? 3.0f : 1.0f + 4.0f * (unit(rng) + 1.0f), 0.0f);
    inputs.emplace_back(-0.0f, 0.5f, 3.0f, 0.0f);
    inputs.emplace_back(1e-30f, 0.9f, 3.0f, 0.0f);
    penumbra::gl::Buffer in = penumbra::gl::Buffer::fromVector(inputs);
    penumbra::gl::Buffer out(inputs.size() * sizeof(glm::vec2));
    glUseProgram(program.id());
    glUniform1ui(0, static_cast<GLuint>(inputs.size()));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, in.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, out.id());
    glDispatchCompute(static_cast<GLuint>((inputs.size() + 63) / 64), 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    const std::vector<glm::vec2> gpu = out.download<glm::vec2>();
    size_t mismatched = 0;
    double max_difference = 0.0;
    for (size_t i = 0; i < inputs.size(); ++i) {
        const glm::vec4 k = inputs[i];
        const float shade = penumbra::bentShade(k.x, k.y, k.z), direct = penumbra::bentDirect(k.x, k.y, k.z);
        // Bit for bit, except the sign of a zero (GLSL's clamp/max may return +0 for -0, which no
        // lighting can see).
        const bool ok = (bits(gpu[i].x) == bits(shade) || (gpu[i].x == 0.0f && shade == 0.0f)) &&
                        (bits(gpu[i].y) == bits(direct) || (gpu[i].y == 0.0f && direct == 0.0f));
        const double d = std::max(std::abs(double(gpu[i].x) - shade), std::abs(double(gpu[i].y) - direct));
        max_difference = std::max(max_difference, std::isfinite(d) ? d : 1e30);
        if (!ok && ++mismatched <= 5)
            MESSAGE("input " << i << " (" << k.x << ", " << k.y << ", " << k.z << "): GPU " << gpu[i].x << ", " << gpu[i].y
                             << " CPU " << shade << ", " << direct);
    }
    MESSAGE(mismatched << " GPU != CPU, largest difference " << max_difference);
    PENUMBRA_CHECK_BITWISE("penumbraBentShade/penumbraBentDirect GPU == CPU twin bit for bit", mismatched == 0);
    CHECK(max_difference <= 1e-4);
}
