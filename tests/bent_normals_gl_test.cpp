// bent_normals.glsl on the GPU: bent_normals.comp.glsl's l_bend per vertex and penumbraBentShade /
// penumbraBentDirect equal the CPU twins bit for bit (bitwise tier, support/gl_test_support.hpp:
// llvmpipe rounds float correctly); on any driver they agree within 1e-4 (portable tier: GLSL's
// division and sqrt are within 3 ulp, FMA contraction is allowed, and these are short chains of
// values of magnitude <= a few units), the back-face guarantee does not change.
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
#include <vector>

namespace {

uint32_t bits(float f) {
    uint32_t b;
    std::memcpy(&b, &f, 4);
    return b;
}

}  // namespace

TEST_CASE("GPU: bent_normals.comp.glsl l_bend == bentLight bit for bit (torus knot, point and sphere light)") {
    penumbra::test::context();
    const penumbra::gl::Program program = penumbra::gl::buildComputeProgram("penumbra/bent_normals/bent_normals.comp.glsl");
    const penumbra::scene::Scene knot = penumbra::scene::torusKnot(64, false);
    const penumbra::scene::Mesh& mesh = knot.meshes[0];
    const penumbra::BentNormalMesh bent =
        penumbra::bentNormalMesh(mesh.positions.data(), mesh.positions.size(), mesh.indices.data(), mesh.indices.size());
    std::vector<glm::vec4> positions;
    for (const glm::vec3& p : mesh.positions) positions.emplace_back(p, 1.0f);
    penumbra::gl::Buffer position_buffer = penumbra::gl::Buffer::fromVector(positions);
    penumbra::gl::Buffer offsets = penumbra::gl::Buffer::fromVector(bent.offsets);
    penumbra::gl::Buffer faces = penumbra::gl::Buffer::fromVector(bent.faces);
    penumbra::gl::Buffer normals = penumbra::gl::Buffer::fromVector(bent.face_normals);
    penumbra::gl::Buffer output(positions.size() * sizeof(float));
    for (const float radius : {0.0f, knot.light.radius, 2.0f}) {
        CAPTURE(radius);
        penumbra::shared::PenumbraBentParams params{};
        params.light = glm::vec4(knot.light.position, radius);
        params.vertex_count = bent.vertex_count;
        penumbra::gl::Buffer params_buffer(sizeof params, &params);
        glUseProgram(program.id());
        glBindBufferBase(GL_UNIFORM_BUFFER, PENUMBRA_BENT_BINDING_PARAMS, params_buffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_BENT_BINDING_POSITIONS, position_buffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_BENT_BINDING_OFFSETS, offsets.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_BENT_BINDING_FACES, faces.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_BENT_BINDING_FACE_NORMALS, normals.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_BENT_BINDING_OUTPUT, output.id());
        glDispatchCompute((bent.vertex_count + PENUMBRA_BENT_GROUP_SIZE - 1) / PENUMBRA_BENT_GROUP_SIZE, 1, 1);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        const std::vector<float> gpu = output.download<float>();
        size_t mismatched = 0, negative = 0;
        double max_difference = 0.0;
        for (uint32_t v = 0; v < bent.vertex_count; ++v) {
            const float cpu = penumbra::bentLight(bent, v, mesh.positions[v], knot.light.position, radius);
            mismatched += bits(cpu) != bits(gpu[v]);
            negative += cpu < 0.0f;
            const double d = std::abs(double(gpu[v]) - cpu);
            max_difference = std::max(max_difference, std::isfinite(d) ? d : 1e30);
        }
        MESSAGE("radius " << radius << ": " << bent.vertex_count << " vertices, " << negative << " with l_bend < 0, "
                          << mismatched << " GPU != CPU, largest difference " << max_difference);
        PENUMBRA_CHECK_BITWISE("bent normals l_bend GPU == CPU twin bit for bit", mismatched == 0);
        CHECK(max_difference <= 1e-4);
        CHECK(negative > 0);
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
