// Test helper: every entry shader penumbra ships (plus test-only entries under tests/shaders/
// that exercise snippets through their hooks), each with its define permutations, and the set of
// files the assemblies touched so tests can prove every shipped file was compiled.
//
// An entry lists its permutations in comments, one define set per line:
//   // penumbra-permutation: PENUMBRA_FOO=1 PENUMBRA_BAR
// No such line means one permutation with no defines.
#ifndef PENUMBRA_TESTS_SHADER_CATALOG_HPP
#define PENUMBRA_TESTS_SHADER_CATALOG_HPP

#include <penumbra/shader_source.hpp>

#include "support/source_paths.hpp"

#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace penumbra::test {

struct EntryPermutation {
    std::string key;
    ShaderDefines defines;
    std::string label() const {
        std::string s = key;
        for (const auto& d : defines) s += " " + d.name + (d.value.empty() ? "" : "=" + d.value);
        return s;
    }
};

inline bool isEntryKey(const std::string& key) {
    for (const char* suffix : {".comp.glsl", ".vert.glsl", ".geom.glsl", ".frag.glsl", ".tesc.glsl", ".tese.glsl"}) {
        std::string s = suffix;
        if (key.size() > s.size() && key.compare(key.size() - s.size(), s.size(), s) == 0) return true;
    }
    return false;
}

/// The embedded library plus tests/shaders (test-only entries may include shipped snippets).
inline ShaderLibrary catalogLibrary() {
    ShaderLibrary lib = ShaderLibrary::embedded();
    const std::string test_dir = penumbra::test::testShaderDir();
    if (std::filesystem::is_directory(test_dir)) lib.addDirectory(test_dir);
    return lib;
}

inline std::vector<EntryPermutation> entryPermutations(const ShaderLibrary& lib) {
    std::vector<EntryPermutation> out;
    for (const auto& key : lib.keys()) {
        if (!isEntryKey(key)) continue;
        std::istringstream in(lib.source(key));
        std::string line;
        bool any = false;
        const std::string tag = "// penumbra-permutation:";
        while (std::getline(in, line)) {
            size_t at = line.find(tag);
            if (at == std::string::npos) continue;
            any = true;
            EntryPermutation p{key, {}};
            std::istringstream words(line.substr(at + tag.size()));
            std::string word;
            while (words >> word) {
                size_t eq = word.find('=');
                p.defines.push_back(eq == std::string::npos ? ShaderDefine{word, ""}
                                                             : ShaderDefine{word.substr(0, eq), word.substr(eq + 1)});
            }
            out.push_back(p);
        }
        if (!any) out.push_back(EntryPermutation{key, {}});
    }
    return out;
}

/// Shipped keys (embedded) that no assembly in `touched` covered.
inline std::vector<std::string> uncoveredShippedFiles(const std::set<std::string>& touched) {
    std::vector<std::string> missing;
    for (const auto& key : ShaderLibrary::embedded().keys()) {
        if (!touched.count(key)) missing.push_back(key);
    }
    return missing;
}

}  // namespace penumbra::test

#endif
