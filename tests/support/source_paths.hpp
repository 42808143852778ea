// Folders of the source tree that tests and benchmarks read at run time, overridable from the
// environment so that a copied build (tools/gpu_bundle.sh: a machine without this checkout) finds
// them next to itself. No doctest here: benchmarks include it too (through bench_common.hpp).
//
//   testShaderDir():   PENUMBRA_TEST_SHADER_DIR, else <source>/tests/shaders (test-only GLSL
//                      entries; the library's own shaders are embedded in every binary).
//   sharedScenesDir(): PENUMBRA_SHARED_SCENES_DIR, else the folder CMake found beside the
//                      repository (../shared/scenes). Callers skip the OBJ scenes when it is absent.
#ifndef PENUMBRA_TESTS_SUPPORT_SOURCE_PATHS_HPP
#define PENUMBRA_TESTS_SUPPORT_SOURCE_PATHS_HPP

#include <cstdlib>
#include <string>

namespace penumbra::test {

/// The environment variable `name` when set and non-empty, else `fallback`.
inline std::string pathFromEnvironment(const char* name, const char* fallback) {
    const char* env = std::getenv(name);
    return env && *env ? std::string(env) : std::string(fallback);
}

inline std::string testShaderDir() {
#ifdef PENUMBRA_SOURCE_DIR
    return pathFromEnvironment("PENUMBRA_TEST_SHADER_DIR", PENUMBRA_SOURCE_DIR "/tests/shaders");
#else
    return pathFromEnvironment("PENUMBRA_TEST_SHADER_DIR", "tests/shaders");
#endif
}

inline std::string sharedScenesDir() {
#ifdef PENUMBRA_SHARED_SCENES_DIR
    return pathFromEnvironment("PENUMBRA_SHARED_SCENES_DIR", PENUMBRA_SHARED_SCENES_DIR);
#else
    return pathFromEnvironment("PENUMBRA_SHARED_SCENES_DIR", "");
#endif
}

}  // namespace penumbra::test

#endif
