// The shader assembler and dispatch-grid arithmetic: pure C++, no GL context.
#include <penumbra/detail/dispatch.hpp>
#include <penumbra/shader_source.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <cctype>
#include <string>
#include <vector>

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

/// GLSL (and C/C++) text with comments replaced by spaces (newlines kept, so offsets keep lines).
std::string withoutComments(const std::string& text) {
    std::string out = text;
    for (size_t i = 0; i < out.size(); ++i) {
        if (out.compare(i, 2, "//") == 0) {
            while (i < out.size() && out[i] != '\n') out[i++] = ' ';
        } else if (out.compare(i, 2, "/*") == 0) {
            const size_t end = out.find("*/", i + 2);
            const size_t stop = end == std::string::npos ? out.size() : end + 2;
            for (; i < stop; ++i) {
                if (out[i] != '\n') out[i] = ' ';
            }
            --i;
        }
    }
    return out;
}

/// Integer literals above 0x7FFFFFFF (2147483647) without a u/U suffix: GLSL types an unsuffixed
/// integer literal as int, so such a value does not fit (a compile error on strict front ends,
/// silent wrap-around on others; STYLE.md habit 4). Floating-point literals (a '.', an exponent or
/// an f suffix) are skipped. Returns "line N: literal" per hit.
std::vector<std::string> unsuffixedLargeLiterals(const std::string& source) {
    const std::string text = withoutComments(source);
    std::vector<std::string> hits;
    auto ident = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
    size_t i = 0;
    while (i < text.size()) {
        const char c = text[i];
        if (!std::isdigit(static_cast<unsigned char>(c)) || (i > 0 && (ident(text[i - 1]) || text[i - 1] == '.'))) {
            ++i;
            continue;
        }
        // A preprocessing number: digits, letters, '.', and an exponent sign.
        size_t end = i;
        while (end < text.size() &&
               (ident(text[end]) || text[end] == '.' ||
                ((text[end] == '+' || text[end] == '-') && (text[end - 1] == 'e' || text[end - 1] == 'E') &&
                 !(text[i] == '0' && (text[i + 1] == 'x' || text[i + 1] == 'X'))))) {
            ++end;
        }
        const std::string token = text.substr(i, end - i);
        i = end;
        const bool hex = token.size() > 2 && token[0] == '0' && (token[1] == 'x' || token[1] == 'X');
        std::string digits = hex ? token.substr(2) : token;
        std::string suffix;
        while (!digits.empty() && std::isalpha(static_cast<unsigned char>(digits.back())) &&
               !(hex && std::isxdigit(static_cast<unsigned char>(digits.back())))) {
            suffix.insert(suffix.begin(), digits.back());
            digits.pop_back();
        }
        if (!hex && (token.find_first_of(".eE") != std::string::npos || suffix.find_first_of("fF") != std::string::npos)) {
            continue;  // floating point
        }
        if (suffix.find_first_of("uU") != std::string::npos || digits.empty()) continue;
        // Value > 2^31 - 1? Compare without overflow: strip leading zeros, then by length and text.
        const size_t first = digits.find_first_not_of('0');
        const std::string value = first == std::string::npos ? "0" : digits.substr(first);
        const std::string limit = hex ? "7fffffff" : "2147483647";
        std::string lower = value;
        for (char& ch : lower) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
        const bool large = lower.size() > limit.size() || (lower.size() == limit.size() && lower > limit);
        if (large) {
            const size_t line = 1 + static_cast<size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(end), '\n'));
            hits.push_back("line " + std::to_string(line) + ": " + token);
        }
    }
    return hits;
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

TEST_CASE("the unsuffixed-literal scan finds what it must and nothing else") {
    const std::string text = "uint a = 0x80000000;  // 0xFFFFFFFF in a comment\n"
                             "/* 4294967295 in a block comment */ uint b = 4294967295u;\n"
                             "float c = 3000000000.0; float d = 5e9; float e = 2147483648.0f; double g = 1e+10;\n"
                             "int h = 2147483647; int i = 0x7FFFFFFF; uint j = 0XFFFFFFFFU;\n"
                             "uint k = 2147483648; uint l = 0x00000000FFFFFFFF; vec2 v2 = vec2(1); uint x9 = 9;\n";
    const std::vector<std::string> hits = unsuffixedLargeLiterals(text);
    REQUIRE(hits.size() == 3);
    CHECK(hits[0] == "line 1: 0x80000000");
    CHECK(hits[1] == "line 5: 2147483648");
    CHECK(hits[2] == "line 5: 0x00000000FFFFFFFF");
}

TEST_CASE("every shipped GLSL file is guarded and has no unsuffixed large literals") {
    // Every file under shaders/ (the embedded table is checked equal to it above), *_shared.h
    // included: they are GLSL too.
    ShaderLibrary disk;
    disk.addDirectory(std::string(PENUMBRA_SOURCE_DIR) + "/shaders");
    REQUIRE(disk.size() > 0);
    size_t scanned = 0;
    for (const auto& key : disk.keys()) {
        CAPTURE(key);
        std::string list;
        for (const std::string& hit : unsuffixedLargeLiterals(disk.source(key))) list += " [" + hit + "]";
        INFO("unsuffixed integer literals above 0x7FFFFFFF:", list);
        CHECK(list.empty());
        ++scanned;
    }
    MESSAGE("scanned ", scanned, " shader files for unsuffixed large literals");
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

namespace {

// A snippet with a hook check and one include; an entry with a guarded #error of its own.
ShaderLibrary snippetLibrary() {
    ShaderLibrary lib;
    lib.add("penumbra/s/hooked.glsl", "#ifndef S_HOOKED\n#define S_HOOKED\n#include \"penumbra/s/inc.glsl\"\n"
                                      "#ifndef S_HOOK\n#error penumbra/s/hooked.glsl needs the hook S_HOOK\n#endif\n"
                                      "float hooked() { return S_HOOK; }\n#endif\n");
    lib.add("penumbra/s/inc.glsl", "const float s_inc = 1.0;\n");
    lib.add("penumbra/s/entry.comp.glsl", "#ifndef S_PASS\n#error entry needs S_PASS\n#endif\n"
                                          "#include \"penumbra/s/hooked.glsl\"\nvoid main() {}\n");
    return lib;
}

// The 1-based line of `text` on which `what` starts (the test's own count, not the assembler's).
int lineOf(const std::string& text, const std::string& what) {
    const size_t at = text.find(what);
    REQUIRE(at != std::string::npos);
    return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

}  // namespace

TEST_CASE("snippet: #line markers name the snippet's own files and resume the engine's numbering") {
    const ShaderLibrary lib = snippetLibrary();
    penumbra::SnippetPlacement at;
    at.engine_file = "engine/e.comp.glsl";
    at.resume_line = 7;
    const penumbra::ShaderSnippet s = penumbra::assembleSnippet("penumbra/s/hooked.glsl", at, lib);
    INFO(s.text);
    CHECK(s.files == std::vector<std::string>{"engine/e.comp.glsl", "penumbra/s/hooked.glsl", "penumbra/s/inc.glsl"});
    CHECK(s.text.rfind("#line 100001 1 // penumbra-file: penumbra/s/hooked.glsl\n", 0) == 0);
    CHECK(s.text.find("#line 200001 2 // penumbra-file: penumbra/s/inc.glsl\nconst float s_inc") != std::string::npos);
    CHECK(s.text.find("#line 100004 1 // penumbra-file: penumbra/s/hooked.glsl\n#ifndef S_HOOK") != std::string::npos);
    // The engine's source number 0 appears once: the last line, back at the engine's line 7.
    CHECK(count(s.text, " 0 //") == 1);
    const std::string resume = "#line 7 0 // penumbra-resume\n";
    CHECK(s.text.size() > resume.size());
    CHECK(s.text.compare(s.text.size() - resume.size(), resume.size(), resume) == 0);
    penumbra::ShaderAssembly table{s.text, s.files};
    CHECK(table.locate(2, 1) == "penumbra/s/inc.glsl:1");
    CHECK(table.locate(0, 7) == "engine/e.comp.glsl:7");
    CHECK(table.locate(0, 200001) == "penumbra/s/inc.glsl:1");  // a driver that drops the source number

    // Numbers after the engine's own source strings; unused numbers name nothing.
    at.engine_source = 2;
    at.first_source = 5;
    const penumbra::ShaderSnippet moved = penumbra::assembleSnippet("penumbra/s/hooked.glsl", at, lib);
    CHECK(moved.text.rfind("#line 500001 5 // penumbra-file: penumbra/s/hooked.glsl\n", 0) == 0);
    REQUIRE(moved.files.size() == 7);
    CHECK(moved.files[2] == "engine/e.comp.glsl");
    CHECK(moved.files[6] == "penumbra/s/inc.glsl");
    CHECK(penumbra::ShaderAssembly{moved.text, moved.files}.locate(3, 1).empty());
    CHECK(moved.text.find("#line 7 2 // penumbra-resume\n") != std::string::npos);

    // Placements that would mislabel are refused, naming the value.
    penumbra::SnippetPlacement bad;
    bad.engine_source = -1;
    CHECK_THROWS_WITH_AS(penumbra::assembleSnippet("penumbra/s/hooked.glsl", bad, lib), doctest::Contains("is -1"),
                         penumbra::Error);
    bad = {};
    bad.resume_line = -3;
    CHECK_THROWS_WITH_AS(penumbra::assembleSnippet("penumbra/s/hooked.glsl", bad, lib), doctest::Contains("is -3"),
                         penumbra::Error);
    bad = {};
    bad.engine_source = 4;
    bad.first_source = 3;
    CHECK_THROWS_WITH_AS(penumbra::assembleSnippet("penumbra/s/hooked.glsl", bad, lib),
                         doctest::Contains("first_source is 3"), penumbra::Error);
}

TEST_CASE("snippet: without a placement it never reuses the engine's source 0 and says where it resumes") {
    const ShaderLibrary lib = snippetLibrary();
    const penumbra::ShaderSnippet s = penumbra::assembleSnippet("penumbra/s/hooked.glsl", lib);
    INFO(s.text);
    CHECK(s.text.find("#line 1 0") == std::string::npos);
    CHECK(s.text.find(" 0 //") == std::string::npos);
    CHECK(s.text.find("#line 300001 3 // penumbra-resume\n") != std::string::npos);
    REQUIRE(s.files.size() == 4);
    CHECK(s.files[1] == "penumbra/s/hooked.glsl");
    CHECK(s.files[3] == "your shader after penumbra/s/hooked.glsl");
}

TEST_CASE("snippet: pasted into an engine file, the assembler keeps its files and the engine's lines") {
    ShaderLibrary lib = snippetLibrary();
    const penumbra::ShaderSnippet s = penumbra::assembleSnippet("penumbra/s/hooked.glsl", lib);
    const std::string engine = "#version 450\n" + s.extensions + "#define S_HOOK 2.0\n" + s.text +
                               "layout(local_size_x = 1) in;\nvoid main() { float x = hooked(); }\n";
    lib.add("engine/e.comp.glsl", engine);
    const penumbra::ShaderAssembly a = assembleShader("engine/e.comp.glsl", {}, lib);
    INFO(a.text);
    CHECK(a.files == std::vector<std::string>{"engine/e.comp.glsl", "penumbra/s/hooked.glsl", "penumbra/s/inc.glsl"});
    // The snippet's markers renumbered into the assembly's table, the comments gone.
    CHECK(a.text.find("penumbra-file") == std::string::npos);
    CHECK(a.text.find("#line 100001 1\n#ifndef S_HOOKED") != std::string::npos);
    // After the snippet the engine's numbering resumes at the line the engine text has there.
    const int main_line = lineOf(engine, "void main()");
    CHECK(a.text.find("#line " + std::to_string(main_line - 1) + " 0\nlayout(local_size_x") != std::string::npos);
    const std::string log = a.annotateLog("1:5(1): preprocessor error: #error\n0:" + std::to_string(main_line) +
                                          "(15): error: x\n");
    CHECK(log.find("[penumbra/s/hooked.glsl:5]") != std::string::npos);
    CHECK(a.annotateLog("0:100005(1): error: dropped source\n").find("[penumbra/s/hooked.glsl:5]") != std::string::npos);
    CHECK(log.find("[engine/e.comp.glsl:" + std::to_string(main_line) + "]") != std::string::npos);
    // A later #include of a file the snippet already holds is skipped like any repeat.
    lib.add("engine/twice.comp.glsl", engine + "#include \"penumbra/s/inc.glsl\"\n");
    CHECK(count(assembleShader("engine/twice.comp.glsl", {}, lib).text, "const float s_inc") == 1);
    lib.add("engine/bad.comp.glsl", "#line 3 1 // penumbra-file: \n");
    CHECK_THROWS_WITH_AS(assembleShader("engine/bad.comp.glsl", {}, lib), doctest::Contains("engine/bad.comp.glsl:1"),
                         penumbra::Error);
}

TEST_CASE("snippet: a missing hook's #error names the hook and the include order") {
    const ShaderLibrary lib = snippetLibrary();
    const std::string order = " [penumbra: hook S_HOOK is not defined where the snippet starts. Order: version "
                              "line, extension lines, your hook defines, then the snippet text or its include line]";
    const std::string flattened = penumbra::assembleSnippet("penumbra/s/hooked.glsl", lib).text;
    CHECK(flattened.find("#error penumbra/s/hooked.glsl needs the hook S_HOOK" + order + "\n") != std::string::npos);
    // Included by an entry: the snippet's hook error gets it, the entry's own define check does not.
    const std::string entry = assembleShader("penumbra/s/entry.comp.glsl", {{"S_PASS", "1"}}, lib).text;
    CHECK(entry.find("#error penumbra/s/hooked.glsl needs the hook S_HOOK" + order + "\n") != std::string::npos);
    CHECK(entry.find("#error entry needs S_PASS\n") != std::string::npos);
}
