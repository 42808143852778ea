// libFuzzer target on the OBJ loader (penumbra/scene/obj.hpp, parseObj from memory).
//
// Contract checked: on any bytes, parseObj either returns a scene whose meshes pass
// validateMesh (finite positions, unit normals, indices in range, no repeated index), or throws
// penumbra::Error. Anything else (another exception, a crash, ASan/UBSan report, a hang) is a bug.
//
// Built by tests/fuzz/CMakeLists.txt with clang++ -fsanitize=fuzzer,address,undefined when clang
// and libFuzzer are there, tinyobjloader's implementation compiled into this file (so it is
// instrumented too); otherwise with the project's compiler and replay_main.cpp, which replays the
// seed corpus and deterministic mutations of it. ctest runs it briefly (label `fuzz`).
//   Reproduce a finding: build/tests/fuzz/obj_fuzz crash-<hash>
#include <penumbra/scene/obj.hpp>

#ifdef PENUMBRA_OBJ_FUZZ_TINYOBJ_IMPLEMENTATION
// tiny_obj_loader.h's implementation part sits outside its include guard: a second inclusion
// with the macro compiles just the implementation, instrumented like the rest.
#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>
#endif

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    // The last byte picks the options, so both normalising and raw paths are explored.
    penumbra::scene::ObjOptions options;
    options.normalize = size == 0 || (data[size - 1] & 1) == 0;
    options.ground = size == 0 || (data[size - 1] & 2) == 0;
    penumbra::scene::Scene scene;
    try {
        scene = penumbra::scene::parseObj(text, "fuzz.obj", options);
    } catch (const penumbra::Error&) {
        return 0;  // the one allowed failure
    }
    // Accepted input: every mesh must be well formed (throws, hence aborts the fuzzer, if not).
    for (const penumbra::scene::Mesh& mesh : scene.meshes) penumbra::scene::validateMesh(mesh);
    return 0;
}
