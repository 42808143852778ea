// A consumer of the penumbra package: assembles one shader from the embedded table (and, when
// given, from the installed shader directory) and checks the result. Exit code 0 = pass.
#define PENUMBRA_SCAN_NO_GL  // setup + CPU twin only: no GL loader in this consumer
#include <penumbra/scan.hpp>     // also proves the *_shared.h headers are on the include path
#include <penumbra/shader_source.hpp>
#include <penumbra/version.hpp>

#include <cstdio>
#include <string>

int main(int argc, char** argv) {
    const std::string key = "penumbra/common/copy.comp.glsl";
    penumbra::ShaderAssembly assembly = penumbra::assembleShader(key, {{"PENUMBRA_COPY_GROUP_SIZE", "128"}});
    bool ok = assembly.text.rfind("#version 450\n", 0) == 0 &&
              assembly.text.find("uint penumbraLinearGroup()") != std::string::npos &&
              assembly.text.find("#define PENUMBRA_COPY_GROUP_SIZE 128") != std::string::npos;
    // A block header's pure setup and CPU twin work from the package too.
    const uint32_t in[4] = {1, 2, 3, 4};
    uint32_t out[4] = {};
    penumbra::scanCpu(in, out, 4, penumbra::ScanKind::Exclusive);
    ok = ok && out[3] == 6 && penumbra::planScan(1u << 20).scratch_bytes > 0;
    if (argc > 1) {  // the installed shaders/ directory must hold the same text
        penumbra::ShaderLibrary disk;
        disk.addDirectory(argv[1]);
        ok = ok && penumbra::assembleShader(key, {{"PENUMBRA_COPY_GROUP_SIZE", "128"}}, disk).text == assembly.text;
    }
    std::printf("penumbra %d.%d.%d consumer: %s (%zu embedded files)\n", penumbra::kVersionMajor,
                penumbra::kVersionMinor, penumbra::kVersionPatch, ok ? "ok" : "FAILED",
                penumbra::ShaderLibrary::embedded().size());
    return ok ? 0 : 1;
}
