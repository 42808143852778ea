// The shader assembler and dispatch-grid arithmetic: pure C++, no GL context.
#include <penumbra/detail/dispatch.hpp>
#include <penumbra/shader_source.hpp>

#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>

using penumbra::assembleShader;
using penumbra::ShaderLibrary;

namespace {

ShaderLibrary smallLibrary() {
    ShaderLibrary lib;
    lib.add("penumbra/a/a.comp.glsl",
            "// entry\n#include \"penumbra/a/b.glsl\"\nvoid main() { b(); }\n#include \"penumbra/a/c.glsl\"\n");
    lib.add("penumbra/a/b.glsl", "#ifndef B\n#define B\n#extension GL_KHR_shader_subgroup_basic : enable\n"
                                 "#include \"penumbra/a/c.glsl\"\nvoid b() {}\n#endif\n");
    lib.add("penumbra/a/c.glsl", "int c_value = 3;\n");
    return lib;
}

size_t count(const std::string& text, const std::string& what) {
    size_t n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
}

}  // namespace

TEST_CASE("assembler: version first, extensions hoisted, defines injected, includes pasted once") {
    const ShaderLibrary lib = smallLibrary();
    auto a = assembleShader("penumbra/a/a.comp.glsl", {{"N", "4"}, {"FLAG", ""}}, lib);
    CHECK(a.text.rfind("#version 450\n#extension GL_KHR_shader_subgroup_basic : enable\n#define N 4\n#define FLAG\n",
                       0) == 0);
    CHECK(count(a.text, "int c_value = 3;") == 1);
    CHECK(count(a.text, "void b() {}") == 1);
    REQUIRE(a.files.size() == 3);
    CHECK(a.files[0] == "penumbra/a/a.comp.glsl");
    CHECK(a.files[1] == "penumbra/a/b.glsl");
    CHECK(a.files[2] == "penumbra/a/c.glsl");
    // After the include of b at line 2 of a, numbering resumes at line 3 of file 0.
    CHECK(a.text.find("#line 3 0\nvoid main() { b(); }") != std::string::npos);
    CHECK(a.locate(1, 5) == "penumbra/a/b.glsl:5");
    CHECK(a.locate(7, 1).empty());
}

TEST_CASE("assembler: an entry's own #version wins and keeps line numbers") {
    ShaderLibrary lib;
    lib.add("e.comp.glsl", "#version 460\nvoid main() {}\n");
    auto a = assembleShader("e.comp.glsl", {}, lib);
    CHECK(a.text.rfind("#version 460\n", 0) == 0);
    CHECK(count(a.text, "#version") == 1);
    CHECK(a.text.find("#line 1 0\n\nvoid main() {}") != std::string::npos);
}

TEST_CASE("assembler: errors name the problem") {
    ShaderLibrary lib;
    lib.add("cycle_a.glsl", "#include \"cycle_b.glsl\"\n");
    lib.add("cycle_b.glsl", "#include \"cycle_a.glsl\"\n");
    lib.add("versioned.glsl", "#version 450\n");
    lib.add("uses_versioned.comp.glsl", "#include \"versioned.glsl\"\n");
    lib.add("missing.comp.glsl", "#include \"nope.glsl\"\n");
    lib.add("malformed.comp.glsl", "#include nope\n");
    CHECK_THROWS_WITH_AS(assembleShader("cycle_a.glsl", {}, lib), doctest::Contains("cycle"), penumbra::Error);
    CHECK_THROWS_WITH_AS(assembleShader("uses_versioned.comp.glsl", {}, lib), doctest::Contains("#version"),
                         penumbra::Error);
    CHECK_THROWS_WITH_AS(assembleShader("missing.comp.glsl", {}, lib), doctest::Contains("nope.glsl"),
                         penumbra::Error);
    CHECK_THROWS_WITH_AS(assembleShader("malformed.comp.glsl", {}, lib), doctest::Contains("malformed #include"),
                         penumbra::Error);
    CHECK_THROWS_WITH_AS(assembleShader("absent.comp.glsl", {}, lib), doctest::Contains("absent.comp.glsl"),
                         penumbra::Error);
    lib.add("ok.comp.glsl", "void main() {}\n");
    CHECK_THROWS_AS(assembleShader("ok.comp.glsl", {{"1BAD", ""}}, lib), penumbra::Error);
    CHECK_THROWS_AS(assembleShader("ok.comp.glsl", {{"GOOD", "a\nb"}}, lib), penumbra::Error);
}

TEST_CASE("assembler: driver logs are annotated with key:line") {
    const ShaderLibrary lib = smallLibrary();
    auto a = assembleShader("penumbra/a/a.comp.glsl", {}, lib);
    const std::string log = a.annotateLog("1:4(3): error: `x' undeclared\n0(2) : error C0000: nv style\nERROR: 2:1: 'y'\n");
    CHECK(log.find("[penumbra/a/b.glsl:4]") != std::string::npos);
    CHECK(log.find("[penumbra/a/a.comp.glsl:2]") != std::string::npos);
    CHECK(log.find("[penumbra/a/c.glsl:1]") != std::string::npos);
}

TEST_CASE("embedded table and shaders/ directory hold the same files") {
    const ShaderLibrary& embedded = ShaderLibrary::embedded();
    REQUIRE(embedded.size() > 0);
    ShaderLibrary disk;
    disk.addDirectory(std::string(PENUMBRA_SOURCE_DIR) + "/shaders");
    CHECK(disk.keys() == embedded.keys());
    for (const auto& key : embedded.keys()) {
        CAPTURE(key);
        CHECK(disk.source(key) == embedded.source(key));
    }
    CHECK(penumbra::shaders::source("penumbra/common/dispatch.glsl").find("penumbraLinearGroup") != std::string::npos);
    CHECK_THROWS_AS(penumbra::shaders::source("penumbra/none.glsl"), penumbra::Error);
    CHECK_THROWS_AS(disk.addDirectory("/definitely/not/here"), penumbra::Error);
}

TEST_CASE("every shipped GLSL file is guarded and has no unsuffixed large literals") {
    for (const auto& key : ShaderLibrary::embedded().keys()) {
        CAPTURE(key);
        const std::string& text = ShaderLibrary::embedded().source(key);
        const bool entry = key.find(".comp.glsl") != std::string::npos || key.find(".vert.glsl") != std::string::npos ||
                           key.find(".geom.glsl") != std::string::npos || key.find(".frag.glsl") != std::string::npos;
        if (!entry) CHECK(text.find("#ifndef PENUMBRA_") != std::string::npos);
        if (!entry) CHECK(text.find("void main") == std::string::npos);
        if (!entry) CHECK(text.find("#version") == std::string::npos);  // snippets get it from the assembler
    }
}

TEST_CASE("foldDispatch respects the per-dimension limit") {
    using penumbra::detail::foldDispatch;
    auto g0 = foldDispatch(0);
    CHECK(g0.x == 0);
    CHECK(g0.y == 0);
    for (uint64_t groups : {1ull, 2ull, 65534ull, 65535ull, 65536ull, 65537ull, 131071ull, 1000000ull,
                            65535ull * 65535ull}) {
        CAPTURE(groups);
        auto g = foldDispatch(groups);
        CHECK(g.x >= 1);
        CHECK(g.x <= 65535u);
        CHECK(g.y <= 65535u);
        CHECK(uint64_t(g.x) * g.y >= groups);
        CHECK(uint64_t(g.x) * g.y - groups < g.x);  // less than one idle row
    }
    CHECK_THROWS_AS(foldDispatch(65535ull * 65535ull + 1), penumbra::Error);
    CHECK(foldDispatch(10, 3, 4).x == 3);
    CHECK_THROWS_AS(foldDispatch(13, 3, 4), penumbra::Error);
}
