// GLSL twin of the per-pixel light-sample selection (shaders/penumbra/light_samples/select.glsl)
// against the CPU (penumbra/light_samples.hpp): set, rotation hash and float turn for a 64 x 64
// grid x 4 frames, several set counts and seeds, near the origin and near 2^32. Integer
// arithmetic and an exact float conversion: bit for bit on any conformant driver.
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/shader.hpp>
#include <penumbra/light_samples.hpp>

#include "support/gl_test_support.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

TEST_CASE("GPU: penumbraLightSampleSet / RotationHash / RotationTurns == the CPU for 64 x 64 pixels x 4 frames") {
    penumbra::test::context();
    penumbra::ShaderLibrary lib = penumbra::ShaderLibrary::embedded();
    lib.addDirectory(penumbra::test::testShaderDir());
    const penumbra::gl::Program program = penumbra::gl::buildComputeProgram("light_samples/select_test.comp.glsl", {}, lib);
    const uint32_t width = 64, height = 64, frames = 4;
    struct Case {
        uint32_t sets, seed, origin_x, origin_y, frame0;
    };
    const Case cases[] = {
        {8, 0, 0, 0, 0},          {1, 1, 0, 0, 0},        {4, 2, 0, 0, 7},         {5, 3, 100, 200, 1},
        {13, 0xdeadbeefu, 0, 0, 0}, {64, 4, 0, 0, 1000}, {0, 5, 0, 0, 0},
        {7, 6, 0xffffffc0u, 0xffffffc0u, 0xfffffffeu},  // wrap-around of pixel and frame arithmetic
    };
    size_t compared = 0, mismatched = 0;
    for (const Case& k : cases) {
        CAPTURE(k.sets);
        CAPTURE(k.seed);
        penumbra::gl::Buffer results(size_t(width) * height * frames * 4 * sizeof(uint32_t));
        results.fill(0xFFFFFFFFu);
        glUseProgram(program.id());
        glUniform2ui(0, width, height);
        glUniform1ui(1, k.sets);
        glUniform1ui(2, k.seed);
        glUniform2ui(3, k.origin_x, k.origin_y);
        glUniform1ui(4, k.frame0);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, results.id());
        glDispatchCompute(width / 8, height / 8, frames);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        const std::vector<uint32_t> words = results.download<uint32_t>();
        for (uint32_t f = 0; f < frames; ++f)
            for (uint32_t y = 0; y < height; ++y)
                for (uint32_t x = 0; x < width; ++x) {
                    const uint32_t px = x + k.origin_x, py = y + k.origin_y, frame = k.frame0 + f;
                    const uint32_t* w = &words[4 * ((size_t(f) * height + y) * width + x)];
                    const float turns = penumbra::lightSampleRotationTurnsFloat(px, py, frame, k.seed);
                    uint32_t turn_bits;
                    std::memcpy(&turn_bits, &turns, 4);
                    const bool ok = w[0] == penumbra::lightSampleSet(px, py, frame, k.sets) &&
                                    w[1] == penumbra::lightSampleRotationHash(px, py, frame, k.seed) &&
                                    w[2] == turn_bits && w[3] == penumbra::lightSampleSetStride(k.sets);
                    if (!ok && ++mismatched <= 5)
                        MESSAGE("pixel (", px, ", ", py, ") frame ", frame, ": GPU ", w[0], " ", w[1], " ", w[2], " ", w[3],
                                ", CPU ", penumbra::lightSampleSet(px, py, frame, k.sets), " ",
                                penumbra::lightSampleRotationHash(px, py, frame, k.seed), " ", turn_bits);
                    ++compared;
                }
    }
    MESSAGE(compared, " pixel-frames compared");
    CHECK(mismatched == 0);
    CHECK(compared == sizeof(cases) / sizeof(cases[0]) * width * height * frames);
}
