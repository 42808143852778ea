// Every entry shader permutation compiles and links on the real driver (ctest runs this once per
// backend); compile errors name the snippet and line; the shared compute copy works across the
// 65 535-group dispatch limit.
#include "shader_catalog.hpp"

#include <penumbra/detail/dispatch.hpp>
#include <penumbra/gl/headless.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/shader.hpp>

#include "support/gl_test_support.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cstdlib>
#include <numeric>
#include <random>

using penumbra::test::context;

TEST_CASE("the driver compiles every entry shader permutation; every shipped file is covered") {
    context();
    const penumbra::ShaderLibrary lib = penumbra::test::catalogLibrary();
    std::set<std::string> touched;
    size_t compiled = 0;
    for (const auto& entry : penumbra::test::entryPermutations(lib)) {
        CAPTURE(entry.label());
        GLuint shader = 0;
        CHECK_NOTHROW(shader = penumbra::gl::compileShader(penumbra::gl::stageFromKey(entry.key), entry.key,
                                                            entry.defines, lib));
        if (shader) {
            glDeleteShader(shader);
            ++compiled;
        }
        auto files = penumbra::assembleShader(entry.key, entry.defines, lib).files;
        touched.insert(files.begin(), files.end());
        // Compute entries must also link on their own.
        if (penumbra::gl::stageFromKey(entry.key) == GL_COMPUTE_SHADER) {
            CHECK_NOTHROW(penumbra::gl::buildComputeProgram(entry.key, entry.defines, lib));
        }
    }
    MESSAGE("compiled ", compiled, " permutations on ", context().renderer());
    const auto missing = penumbra::test::uncoveredShippedFiles(touched);
    std::string list;
    for (const auto& m : missing) list += " " + m;
    INFO("shipped shader files no entry includes:", list);
    CHECK(missing.empty());
}

TEST_CASE("a compile error names the snippet file and line") {
    context();
    penumbra::ShaderLibrary lib;
    lib.add("t/broken.glsl", "#ifndef T_BROKEN\n#define T_BROKEN\nfloat f() {\n  return undeclared_thing;\n}\n#endif\n");
    lib.add("t/entry.comp.glsl", "layout(local_size_x = 1) in;\n#include \"t/broken.glsl\"\nvoid main() { f(); }\n");
    try {
        penumbra::gl::buildComputeProgram("t/entry.comp.glsl", {{"PENUMBRA_PROBE", "1"}}, lib);
        FAIL("expected a compile error");
    } catch (const penumbra::Error& e) {
        const std::string what = e.what();
        INFO(what);
        CHECK(what.find("t/entry.comp.glsl") != std::string::npos);
        CHECK(what.find("[t/broken.glsl:4]") != std::string::npos);
        // Mesa drops the source number on "undeclared" errors; the line must still name broken.glsl.
        CHECK(what.find("[t/entry.comp.glsl:4]") == std::string::npos);
        CHECK(what.find("PENUMBRA_PROBE=1") != std::string::npos);
    }
    lib.add("t/link.vert.glsl", "layout(location=0) out vec4 a;\nvoid main() { gl_Position = vec4(0); a = vec4(1); }\n");
    lib.add("t/link.frag.glsl", "layout(location=0) in ivec4 a;\nlayout(location=0) out vec4 c;\nvoid main() { c = vec4(a); }\n");
    CHECK_THROWS_AS(penumbra::gl::buildProgram({"t/link.vert.glsl", "t/link.frag.glsl"}, {}, lib), penumbra::Error);
    CHECK_THROWS_AS(penumbra::gl::compileShader(0, "t/broken.glsl", {}, lib), penumbra::Error);
}

TEST_CASE("compute copy across the 65 535-group limit") {
    context();
    std::mt19937 rng(penumbra::test::testSeed());
    penumbra::gl::Program copy = penumbra::gl::buildComputeProgram("penumbra/common/copy.comp.glsl");
    for (size_t count : {size_t(0), size_t(1), size_t(255), size_t(256), size_t(257), size_t(65535 * 256 + 3)}) {
        CAPTURE(count);
        std::vector<uint32_t> data(count * 4);
        for (auto& v : data) v = rng();
        auto src = penumbra::gl::Buffer::fromVector(data);
        penumbra::gl::Buffer dst(data.size() * 4);
        dst.fill(0xdeadbeefu);  // poison
        auto grid = penumbra::detail::foldDispatch(penumbra::detail::divUp(count, 256));
        copy.use();
        glUniform1ui(0, static_cast<GLuint>(count));
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, src.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, dst.id());
        if (grid.groups) glDispatchCompute(grid.x, grid.y, 1);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        CHECK(dst.download<uint32_t>() == data);
        penumbra::gl::checkErrors("compute copy");
    }
}

TEST_CASE("full-screen triangle renders its UV gradient") {
    context();
    penumbra::gl::Program p =
        penumbra::gl::buildProgram({"penumbra/common/fullscreen.vert.glsl", "penumbra/common/fullscreen_uv.frag.glsl"});
    penumbra::gl::Texture color(GL_TEXTURE_2D);
    glTextureStorage2D(color.id(), 1, GL_RGBA32F, 8, 4);
    GLuint fbo = 0, vao = 0;
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, color.id(), 0);
    REQUIRE(glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE);
    glCreateVertexArrays(1, &vao);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, 8, 4);
    glBindVertexArray(vao);
    p.use();
    glDrawArrays(GL_TRIANGLES, 0, 3);
    std::vector<float> pixels(8 * 4 * 4);
    glGetTextureImage(color.id(), 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(pixels.size() * 4), pixels.data());
    for (int y = 0; y < 4; ++y) {
        for (int x = 0; x < 8; ++x) {
            CHECK(pixels[(y * 8 + x) * 4 + 0] == doctest::Approx((x + 0.5) / 8).epsilon(1e-5));
            CHECK(pixels[(y * 8 + x) * 4 + 1] == doctest::Approx((y + 0.5) / 4).epsilon(1e-5));
        }
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &fbo);
    glDeleteVertexArrays(1, &vao);
    penumbra::gl::checkErrors("fullscreen triangle");
}

namespace {

// The 1-based line of `text` on which `what` starts (counted here, not by the assembler).
int lineOf(const std::string& text, const std::string& what) {
    const size_t at = text.find(what);
    REQUIRE(at != std::string::npos);
    return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

int lineCount(const std::string& text) { return static_cast<int>(std::count(text.begin(), text.end(), '\n')); }

const char* const kEngineTail = "layout(std430, binding = 0) buffer Data { uint data[]; };\n"
                                "void main() {\n"
                                "    uint i = gl_LocalInvocationID.x;\n"
                                "    data[i] = penumbraScanWorkgroupExclusive(data[i]);\n"
                                "}\n";

}  // namespace

TEST_CASE("a snippet pasted before its hooks fails naming the snippet's file, its line and the order") {
    context();
    const std::string key = "penumbra/scan/workgroup.glsl";
    const std::string& file = penumbra::shaders::source(key);
    const int error_line = lineOf(file, "#error penumbra/scan/workgroup.glsl needs the hook PENUMBRA_SCAN_GROUP_SIZE");
    // README flow: the engine's text (snippet pasted before the hook's #define) goes through a library.
    const penumbra::ShaderSnippet snippet = penumbra::assembleSnippet(key);
    const std::string engine = "#version 450\n" + snippet.extensions + snippet.text +
                               "layout(local_size_x = 256) in;\n#define PENUMBRA_SCAN_GROUP_SIZE 256\n" + kEngineTail;
    penumbra::ShaderLibrary library;
    library.add("engine/my_scan.comp.glsl", engine);
    try {
        penumbra::gl::buildComputeProgram("engine/my_scan.comp.glsl", {}, library);
        FAIL("expected a compile error");
    } catch (const penumbra::Error& e) {
        const std::string what = e.what();
        INFO(what);
        CHECK(what.find("[" + key + ":" + std::to_string(error_line) + "]") != std::string::npos);
        CHECK(what.find("hook PENUMBRA_SCAN_GROUP_SIZE is not defined where the snippet starts. Order:") !=
              std::string::npos);
        CHECK(what.find("[engine/my_scan.comp.glsl:") == std::string::npos);
    }
    // Engine code after the snippet keeps the engine file's own lines (those of the text it added).
    const std::string broken = "#version 450\n" + snippet.extensions + "layout(local_size_x = 256) in;\n"
                               "#define PENUMBRA_SCAN_GROUP_SIZE 256\n" + snippet.text +
                               "void main() {\n    uint x = undeclared_thing;\n}\n";
    library.add("engine/broken.comp.glsl", broken);
    try {
        penumbra::gl::buildComputeProgram("engine/broken.comp.glsl", {}, library);
        FAIL("expected a compile error");
    } catch (const penumbra::Error& e) {
        const std::string what = e.what();
        INFO(what);
        CHECK(what.find("[engine/broken.comp.glsl:" + std::to_string(lineOf(broken, "undeclared_thing")) + "]") !=
              std::string::npos);
    }
}

TEST_CASE("an engine's own text with a snippet pasted after the wrong line: errors use its file table") {
    context();
    const std::string key = "penumbra/scan/workgroup.glsl";
    const int file_lines = lineCount(penumbra::shaders::source(key));
    // The snippet pasted before the layout(local_size_x ...) line it checks its hook against.
    const std::string head = "#version 450\n#define PENUMBRA_SCAN_GROUP_SIZE 256\n";
    penumbra::SnippetPlacement at;
    at.engine_file = "engine/my_scan.comp.glsl";
    at.resume_line = lineCount(head) + 1;  // the snippet takes no line of the engine's own
    const penumbra::ShaderSnippet snippet = penumbra::assembleSnippet(key, at);
    REQUIRE(snippet.extensions.empty());
    const std::string engine = head + snippet.text + "layout(local_size_x = 256) in;\n" + kEngineTail;
    try {
        glDeleteShader(penumbra::gl::compileShaderText(GL_COMPUTE_SHADER, at.engine_file,
                                                       penumbra::ShaderAssembly{engine, snippet.files}));
        FAIL("expected a compile error");
    } catch (const penumbra::Error& e) {
        const std::string what = e.what();
        INFO(what);
        const size_t label = what.find("[" + key + ":");
        REQUIRE(label != std::string::npos);
        const int line = std::atoi(what.c_str() + label + key.size() + 2);
        CHECK(line >= 1);
        CHECK(line <= file_lines);  // within the snippet's file, not past an end
        CHECK(what.find("[engine/my_scan.comp.glsl:") == std::string::npos);
    }
    // With the layout first it compiles; an engine error after the snippet gets the engine's line.
    const std::string good_head = "#version 450\nlayout(local_size_x = 256) in;\n#define PENUMBRA_SCAN_GROUP_SIZE 256\n";
    at.resume_line = lineCount(good_head) + 1;
    const penumbra::ShaderSnippet placed = penumbra::assembleSnippet(key, at);
    const std::string tail = "void main() {\n    uint x = undeclared_thing;\n}\n";
    const int expected = at.resume_line + 1;  // line 2 of the tail, in the engine's own numbering
    const std::string expected_label = "[engine/my_scan.comp.glsl:" + std::to_string(expected) + "]";
    CHECK_THROWS_WITH_AS(penumbra::gl::compileShaderText(GL_COMPUTE_SHADER, at.engine_file,
                                                         penumbra::ShaderAssembly{good_head + placed.text + tail,
                                                                                  placed.files}),
                         doctest::Contains(expected_label.c_str()),
                         penumbra::Error);
    GLuint ok = 0;
    CHECK_NOTHROW(ok = penumbra::gl::compileShaderText(GL_COMPUTE_SHADER, at.engine_file,
                                                       penumbra::ShaderAssembly{good_head + placed.text + kEngineTail,
                                                                                placed.files}));
    glDeleteShader(ok);
    CHECK_THROWS_AS(penumbra::gl::compileShaderText(0, at.engine_file, penumbra::ShaderAssembly{}), penumbra::Error);
}
