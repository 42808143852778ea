// penumbra — shader sources and the GLSL assembler (pure C++, no GL needed).
//
// Integration summary
//   Every GLSL file ships two ways under one key space, the path below `shaders/`
//   ("penumbra/scan/scan.comp.glsl"):
//     * embedded: CMake generates <penumbra/detail/embedded_shaders.inc> from shaders/ (the
//       penumbra::penumbra target puts it on the include path, and it is installed with the
//       package), so penumbra::shaders::source(key) works with no files at run time;
//     * on disk: ShaderLibrary::addDirectory(path) reads the same keys from a directory, for
//       hot reload or engine-side overrides (a later add wins over an earlier one).
//   assemble(key, defines) produces one compilable string: `#version` first (the entry file's own,
//   else `#version 450`), then the `#extension` lines the files ask for, then the injected
//   defines, then the text with every `#include "penumbra/..."` pasted in (each file once per
//   assembly; files keep include guards anyway) and `#line L F` markers, F being the index of the
//   file in Assembly::files, so a driver's "F:L" message maps back to key:line (see
//   Assembly::locate and gl/shader.hpp).
#ifndef PENUMBRA_SHADER_SOURCE_HPP
#define PENUMBRA_SHADER_SOURCE_HPP

#include "penumbra/error.hpp"
#include "penumbra/shader_defines.hpp"

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#if defined(__has_include)
#if __has_include(<penumbra/detail/embedded_shaders.inc>)
#define PENUMBRA_HAS_EMBEDDED_SHADERS 1
#endif
#endif

namespace penumbra {

/// A key -> GLSL text table. Value-initialised it is empty; ShaderLibrary::embedded() is the
/// table built into the package.
class ShaderLibrary {
public:
    /// The embedded table (empty when the generated header is not on the include path).
    static const ShaderLibrary& embedded() {
        static const ShaderLibrary library = [] {
            ShaderLibrary lib;
#ifdef PENUMBRA_HAS_EMBEDDED_SHADERS
            struct Entry {
                const char* key;
                const char* text;
            };
            static const Entry entries[] = {
#include <penumbra/detail/embedded_shaders.inc>
                {nullptr, nullptr}};
            for (const Entry* e = entries; e->key; ++e) lib.add(e->key, e->text);
#endif
            return lib;
        }();
        return library;
    }

    /// Adds or replaces one file.
    void add(std::string key, std::string text) { files_[std::move(key)] = std::move(text); }

    /// Adds every *.glsl and *.h file below `root`, keyed by its path relative to `root` with '/'.
    /// Throws penumbra::Error when `root` is not a directory.
    void addDirectory(const std::string& root) {
        namespace fs = std::filesystem;
        std::error_code ec;
        PENUMBRA_CHECK(fs::is_directory(root, ec), "penumbra: shader directory '", root, "' does not exist");
        for (const auto& entry : fs::recursive_directory_iterator(root)) {
            if (!entry.is_regular_file()) continue;
            const std::string ext = entry.path().extension().string();
            if (ext != ".glsl" && ext != ".h") continue;
            std::ifstream in(entry.path(), std::ios::binary);
            std::ostringstream text;
            text << in.rdbuf();
            add(fs::relative(entry.path(), root).generic_string(), text.str());
        }
    }

    bool contains(const std::string& key) const { return files_.count(key) != 0; }

    /// The text of `key`; throws penumbra::Error naming the key when it is missing.
    const std::string& source(const std::string& key) const {
        auto it = files_.find(key);
        PENUMBRA_CHECK(it != files_.end(), "penumbra: no shader file '", key, "' in the shader library (",
                       files_.size(), " files)");
        return it->second;
    }

    /// All keys, sorted.
    std::vector<std::string> keys() const {
        std::vector<std::string> out;
        for (const auto& kv : files_) out.push_back(kv.first);
        return out;
    }

    size_t size() const { return files_.size(); }

private:
    std::map<std::string, std::string> files_;
};

namespace shaders {
/// The embedded text of `key` (throws penumbra::Error when missing).
inline const std::string& source(const std::string& key) { return ShaderLibrary::embedded().source(key); }
}  // namespace shaders

/// The assembled text plus what is needed to map driver messages back to files.
struct ShaderAssembly {
    std::string text;
    std::vector<std::string> files;  ///< index = the source-string number used in #line markers

    /// "key:line" for a driver's (file index, line) pair, or "" when out of range.
    std::string locate(int file_index, int line) const {
        if (file_index < 0 || static_cast<size_t>(file_index) >= files.size()) return {};
        return files[static_cast<size_t>(file_index)] + ":" + std::to_string(line);
    }

    /// Rewrites a driver info log: every "F:L" / "F(L)" location that names an assembled file
    /// gets "[key:line]" appended, so an engine programmer sees the snippet that failed.
    std::string annotateLog(const std::string& log) const {
        // Mesa: "0:12(7): error: ..."; NVIDIA: "0(12) : error ..."; glslang: "ERROR: 0:12: ...".
        static const std::regex location(R"((\d+)(?::(\d+)\(\d+\)|\((\d+)\)|:(\d+):))");
        std::istringstream in(log);
        std::string line, out;
        while (std::getline(in, line)) {
            std::smatch m;
            out += line;
            if (std::regex_search(line, m, location)) {
                int file = std::atoi(m[1].str().c_str());
                std::string l = m[2].matched ? m[2].str() : m[3].matched ? m[3].str() : m[4].str();
                std::string where = locate(file, std::atoi(l.c_str()));
                if (!where.empty()) out += "  [" + where + "]";
            }
            out += '\n';
        }
        return out;
    }
};

namespace detail {

inline std::string trimLeft(const std::string& s) {
    size_t i = 0;
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    return s.substr(i);
}

// True when `line` is the preprocessor directive `name` (e.g. "include"), allowing "#  include".
inline bool isDirective(const std::string& line, const char* name, std::string* rest) {
    std::string t = trimLeft(line);
    if (t.empty() || t[0] != '#') return false;
    t = trimLeft(t.substr(1));
    size_t n = std::char_traits<char>::length(name);
    if (t.compare(0, n, name) != 0) return false;
    if (t.size() > n && !std::isspace(static_cast<unsigned char>(t[n]))) return false;
    if (rest) *rest = trimLeft(t.substr(n));
    return true;
}

inline bool validDefineName(const std::string& name) {
    if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0]))) return false;
    for (char c : name) {
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
    }
    return true;
}

class Assembler {
public:
    explicit Assembler(const ShaderLibrary& library) : library_(library) {}

    ShaderAssembly run(const std::string& key, const ShaderDefines& defines) {
        std::string body;
        paste(key, body, 0, key);
        std::string out = (version_.empty() ? std::string("#version 450") : version_) + "\n";
        for (const auto& ext : extensions_) out += ext + "\n";
        for (const auto& d : defines) {
            PENUMBRA_CHECK(validDefineName(d.name), "penumbra: invalid shader define name '", d.name, "'");
            PENUMBRA_CHECK(d.value.find('\n') == std::string::npos, "penumbra: shader define ", d.name,
                           " has a newline in its value");
            out += "#define " + d.name + (d.value.empty() ? "" : " " + d.value) + "\n";
        }
        out += body;
        return ShaderAssembly{std::move(out), std::move(files_)};
    }

private:
    const ShaderLibrary& library_;
    std::string version_;
    std::vector<std::string> extensions_;
    std::vector<std::string> files_;
    std::vector<std::string> stack_;

    void paste(const std::string& key, std::string& out, int depth, const std::string& from) {
        PENUMBRA_CHECK(depth < 32, "penumbra: shader includes nest deeper than 32 levels at '", key, "'");
        for (const auto& open : stack_) {
            PENUMBRA_CHECK(open != key, "penumbra: shader include cycle through '", key, "'");
        }
        for (const auto& done : files_) {
            if (done == key) return;  // each file once per assembly
        }
        PENUMBRA_CHECK(library_.contains(key), "penumbra: shader file '", key, "' not found (included from ",
                       from, ")");
        const int index = static_cast<int>(files_.size());
        files_.push_back(key);
        stack_.push_back(key);
        std::istringstream in(library_.source(key));
        std::string line, rest;
        int number = 0;
        out += "#line 1 " + std::to_string(index) + "\n";
        while (std::getline(in, line)) {
            ++number;
            if (!line.empty() && line.back() == '\r') line.pop_back();
            if (isDirective(line, "version", &rest)) {
                PENUMBRA_CHECK(depth == 0, "penumbra: '", key, ":", number,
                               "' has #version; only entry shaders may (snippets get it from the assembler)");
                version_ = "#version " + rest;
                out += "\n";  // keep line numbers
            } else if (isDirective(line, "extension", &rest)) {
                std::string ext = "#extension " + rest;
                bool seen = false;
                for (const auto& e : extensions_) seen = seen || e == ext;
                if (!seen) extensions_.push_back(ext);
                out += "\n";
            } else if (isDirective(line, "include", &rest)) {
                std::string target;
                if (rest.size() >= 2 && (rest[0] == '"' || rest[0] == '<')) {
                    size_t end = rest.find(rest[0] == '"' ? '"' : '>', 1);
                    if (end != std::string::npos) target = rest.substr(1, end - 1);
                }
                PENUMBRA_CHECK(!target.empty(), "penumbra: malformed #include at ", key, ":", number);
                paste(target, out, depth + 1, key + ":" + std::to_string(number));
                out += "#line " + std::to_string(number + 1) + " " + std::to_string(index) + "\n";
            } else {
                out += line;
                out += '\n';
            }
        }
        stack_.pop_back();
    }
};

}  // namespace detail

/// Assembles `key` from `library` (see the summary at the top of this file). Throws
/// penumbra::Error on a missing file, an include cycle, #version in a snippet or a bad define.
inline ShaderAssembly assembleShader(const std::string& key, const ShaderDefines& defines = {},
                                     const ShaderLibrary& library = ShaderLibrary::embedded()) {
    return detail::Assembler(library).run(key, defines);
}

}  // namespace penumbra

#endif
