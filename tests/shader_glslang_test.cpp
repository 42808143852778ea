// glslangValidator (Khronos' reference GLSL front end) over every entry shader permutation. With
// the driver-compile test (shader_gl_test) this covers every file under shaders/ twice.
#include "shader_catalog.hpp"

#include <doctest/doctest.h>

#include <cstdlib>
#include <fstream>
#include <set>

namespace {

const char* glslangStage(const std::string& key) {
    if (key.find(".comp.glsl") != std::string::npos) return "comp";
    if (key.find(".vert.glsl") != std::string::npos) return "vert";
    if (key.find(".geom.glsl") != std::string::npos) return "geom";
    if (key.find(".frag.glsl") != std::string::npos) return "frag";
    if (key.find(".tesc.glsl") != std::string::npos) return "tesc";
    return "tese";
}

}  // namespace

TEST_CASE("glslangValidator accepts every entry shader permutation and covers every shipped file") {
    namespace fs = std::filesystem;
    const penumbra::ShaderLibrary lib = penumbra::test::catalogLibrary();
    const auto entries = penumbra::test::entryPermutations(lib);
    REQUIRE(!entries.empty());
    fs::create_directories(PENUMBRA_TEST_WORK_DIR);
    std::set<std::string> touched;
    int index = 0;
    for (const auto& entry : entries) {
        CAPTURE(entry.label());
        penumbra::ShaderAssembly assembly = penumbra::assembleShader(entry.key, entry.defines, lib);
        touched.insert(assembly.files.begin(), assembly.files.end());
        const std::string path = std::string(PENUMBRA_TEST_WORK_DIR) + "/shader" + std::to_string(index++) + ".glsl";
        std::ofstream(path) << assembly.text;
        const std::string log = path + ".log";
        const std::string cmd = std::string(PENUMBRA_GLSLANG) + " -S " + glslangStage(entry.key) + " " + path +
                                " > " + log + " 2>&1";
        const int rc = std::system(cmd.c_str());
        std::ifstream in(log);
        std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        INFO("glslangValidator output:\n", assembly.annotateLog(text));
        CHECK(rc == 0);
    }
    MESSAGE("validated ", entries.size(), " entry permutations touching ", touched.size(), " files");
    const auto missing = penumbra::test::uncoveredShippedFiles(touched);
    std::string list;
    for (const auto& m : missing) list += " " + m;
    INFO("shipped shader files no entry includes:", list);
    CHECK(missing.empty());
}
