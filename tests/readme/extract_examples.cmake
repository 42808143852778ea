# Extracts the README's compiled examples into one C++ file (run at configure time; README.md is
# a configure dependency). An example is a ```cpp fence whose first line is `// example: NAME`;
# it must define `bool example_NAME()` (true = it worked). The generated main() creates a
# headless GL context and runs every example, so the README's code is compiled and run in CI.
#   in:  README (path), OUT (path of the .cpp to write)
file(READ "${README}" text)
# CMake lists split on ';' (and brackets group): protect them while the blocks travel as a list.
string(REPLACE ";" "@PENUMBRA_SEMICOLON@" text "${text}")
string(REPLACE "[" "@PENUMBRA_OPEN_BRACKET@" text "${text}")
string(REPLACE "]" "@PENUMBRA_CLOSE_BRACKET@" text "${text}")
string(REGEX MATCHALL "```cpp\n// example: [a-z_]+\n[^`]*```" blocks "${text}")
set(body "// Generated from README.md by tests/readme/extract_examples.cmake: do not edit.\n")
set(calls "")
set(names "")
foreach(block IN LISTS blocks)
    string(REGEX MATCH "// example: ([a-z_]+)" _ "${block}")
    set(name "${CMAKE_MATCH_1}")
    string(REGEX REPLACE "^```cpp\n" "" code "${block}")
    string(REGEX REPLACE "```$" "" code "${code}")
    string(APPEND body "// ---- README example: ${name}\n${code}\n")
    string(APPEND calls "    run(\"${name}\", example_${name});\n")
    list(APPEND names "${name}")
endforeach()
# A fence that opens an example but was not extracted (e.g. a backtick inside it) is an error.
string(REGEX MATCHALL "// example: [a-z_]+" announced "${text}")
list(LENGTH announced announced_count)
list(LENGTH names count)
if(NOT announced_count EQUAL count)
    message(FATAL_ERROR "README.md announces ${announced_count} examples but ${count} could be extracted "
                        "(no backticks inside an example)")
endif()
if(count EQUAL 0)
    message(FATAL_ERROR "README.md holds no ```cpp fence starting with // example: NAME")
endif()
string(APPEND body "
#include <penumbra/gl/headless.hpp>
#include <cstdio>
namespace {
int readme_failures = 0;
void run(const char* name, bool (*example)()) {
    bool ok = false;
    try {
        ok = example();
    } catch (const std::exception& e) {
        std::printf(\"example %s threw: %s\\n\", name, e.what());
    }
    std::printf(\"%s: README example %s\\n\", ok ? \"ok\" : \"FAILED\", name);
    readme_failures += !ok;
}
}  // namespace
int main() {
    penumbra::gl::HeadlessContext context;
${calls}    std::printf(\"%d passed, %d failed\\n\", ${count} - readme_failures, readme_failures);
    return readme_failures == 0 ? 0 : 1;
}
")
string(REPLACE "@PENUMBRA_SEMICOLON@" ";" body "${body}")
string(REPLACE "@PENUMBRA_OPEN_BRACKET@" "[" body "${body}")
string(REPLACE "@PENUMBRA_CLOSE_BRACKET@" "]" body "${body}")
file(WRITE "${OUT}.tmp" "${body}")
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
