// penumbra — compiling assembled shaders into GL programs.
//
// Integration summary
//   needs:    a current GL 4.5 context; PENUMBRA_GL_HEADER (see gl.hpp).
//   produces: gl::Program, an RAII program object (movable, not copyable), from shader keys
//             assembled by penumbra/shader_source.hpp (embedded table or a directory).
//   errors:   a compile or link failure throws penumbra::Error whose message holds the stage, the
//             entry key, the driver's info log with "[key:line]" appended to every location that
//             maps to a snippet, and the define set. compileShaderText does the same for text
//             you put together yourself (a flattened snippet pasted in), with your file table.
#ifndef PENUMBRA_GL_SHADER_HPP
#define PENUMBRA_GL_SHADER_HPP

#include "penumbra/gl/gl.hpp"
#include "penumbra/shader_source.hpp"

#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

namespace penumbra::gl {

/// The GL stage a key's file name implies: *.comp.glsl, *.vert.glsl, *.geom.glsl, *.frag.glsl,
/// *.tesc.glsl, *.tese.glsl. Returns 0 for snippets.
inline GLenum stageFromKey(const std::string& key) {
    struct Suffix {
        const char* text;
        GLenum stage;
    };
    static const Suffix suffixes[] = {{".comp.glsl", GL_COMPUTE_SHADER},  {".vert.glsl", GL_VERTEX_SHADER},
                                      {".geom.glsl", GL_GEOMETRY_SHADER}, {".frag.glsl", GL_FRAGMENT_SHADER},
                                      {".tesc.glsl", GL_TESS_CONTROL_SHADER}, {".tese.glsl", GL_TESS_EVALUATION_SHADER}};
    for (const auto& s : suffixes) {
        const std::string suffix = s.text;
        if (key.size() > suffix.size() && key.compare(key.size() - suffix.size(), suffix.size(), suffix) == 0) {
            return s.stage;
        }
    }
    return 0;
}

inline const char* stageName(GLenum stage) {
    switch (stage) {
        case GL_COMPUTE_SHADER: return "compute";
        case GL_VERTEX_SHADER: return "vertex";
        case GL_GEOMETRY_SHADER: return "geometry";
        case GL_FRAGMENT_SHADER: return "fragment";
        case GL_TESS_CONTROL_SHADER: return "tessellation control";
        case GL_TESS_EVALUATION_SHADER: return "tessellation evaluation";
        default: return "unknown";
    }
}

/// An owned GL program object.
class Program {
public:
    Program() = default;
    explicit Program(GLuint id) : id_(id) {}
    Program(Program&& other) noexcept : id_(std::exchange(other.id_, 0)) {}
    Program& operator=(Program&& other) noexcept {
        if (this != &other) {
            reset();
            id_ = std::exchange(other.id_, 0);
        }
        return *this;
    }
    Program(const Program&) = delete;
    Program& operator=(const Program&) = delete;
    ~Program() { reset(); }

    GLuint id() const { return id_; }
    explicit operator bool() const { return id_ != 0; }
    void use() const { glUseProgram(id_); }
    GLint uniform(const char* name) const { return glGetUniformLocation(id_, name); }
    void reset() {
        if (id_) glDeleteProgram(id_);
        id_ = 0;
    }

private:
    GLuint id_ = 0;
};

namespace detail {

inline std::string definesText(const ShaderDefines& defines) {
    std::string s;
    for (const auto& d : defines) s += (s.empty() ? "" : " ") + d.name + (d.value.empty() ? "" : "=" + d.value);
    return s.empty() ? "(none)" : s;
}

}  // namespace detail

namespace detail {

inline GLuint compileAssembly(GLenum stage, const std::string& name, const ShaderAssembly& assembly,
                              const std::string& defines_text) {
    GLuint shader = glCreateShader(stage);
    PENUMBRA_CHECK(shader != 0, "penumbra: glCreateShader(", stageName(stage), ") failed for ", name);
    const char* text = assembly.text.c_str();
    glShaderSource(shader, 1, &text, nullptr);
    glCompileShader(shader);
    GLint ok = GL_FALSE;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        GLint length = 0;
        glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
        std::string log(static_cast<size_t>(length > 0 ? length : 1), '\0');
        glGetShaderInfoLog(shader, static_cast<GLsizei>(log.size()), nullptr, log.data());
        glDeleteShader(shader);
        log.resize(std::char_traits<char>::length(log.c_str()));
        ::penumbra::detail::fail("penumbra: ", stageName(stage), " shader '", name, "' failed to compile (defines: ",
                                 defines_text, "):\n", assembly.annotateLog(log));
    }
    return shader;
}

}  // namespace detail

/// Compiles one stage; returns the shader object (caller deletes) or throws penumbra::Error.
inline GLuint compileShader(GLenum stage, const std::string& key, const ShaderDefines& defines = {},
                            const ShaderLibrary& library = ShaderLibrary::embedded()) {
    PENUMBRA_CHECK(stage != 0, "penumbra: '", key, "' is not an entry shader (*.comp/vert/geom/frag.glsl)");
    return detail::compileAssembly(stage, key, assembleShader(key, defines, library), detail::definesText(defines));
}

/// Compiles your own text as is (source.text, #version and all); the error log's source numbers
/// are translated through source.files (e.g. ShaderSnippet::files of the snippet you pasted in).
/// Returns the shader object (caller deletes) or throws penumbra::Error naming `name`.
inline GLuint compileShaderText(GLenum stage, const std::string& name, const ShaderAssembly& source) {
    PENUMBRA_CHECK(stage != 0, "penumbra: compileShaderText('", name, "') needs a GL stage, got 0");
    return detail::compileAssembly(stage, name, source, "(your text)");
}

/// Compiles and links the given entry keys (stages inferred from the file names).
inline Program buildProgram(const std::vector<std::string>& keys, const ShaderDefines& defines = {},
                            const ShaderLibrary& library = ShaderLibrary::embedded()) {
    PENUMBRA_CHECK(!keys.empty(), "penumbra: buildProgram needs at least one shader key");
    std::vector<GLuint> shaders;
    try {
        for (const auto& key : keys) shaders.push_back(compileShader(stageFromKey(key), key, defines, library));
    } catch (...) {
        for (GLuint s : shaders) glDeleteShader(s);
        throw;
    }
    Program program(glCreateProgram());
    for (GLuint s : shaders) glAttachShader(program.id(), s);
    glLinkProgram(program.id());
    for (GLuint s : shaders) {
        glDetachShader(program.id(), s);
        glDeleteShader(s);
    }
    GLint ok = GL_FALSE;
    glGetProgramiv(program.id(), GL_LINK_STATUS, &ok);
    if (!ok) {
        GLint length = 0;
        glGetProgramiv(program.id(), GL_INFO_LOG_LENGTH, &length);
        std::string log(static_cast<size_t>(length > 0 ? length : 1), '\0');
        glGetProgramInfoLog(program.id(), static_cast<GLsizei>(log.size()), nullptr, log.data());
        log.resize(std::char_traits<char>::length(log.c_str()));
        std::string names;
        for (const auto& k : keys) names += (names.empty() ? "" : ", ") + k;
        ::penumbra::detail::fail("penumbra: program [", names, "] failed to link (defines: ", detail::definesText(defines), "):\n", log);
    }
    return program;
}

/// Convenience: a compute program from one key.
inline Program buildComputeProgram(const std::string& key, const ShaderDefines& defines = {},
                                   const ShaderLibrary& library = ShaderLibrary::embedded()) {
    return buildProgram({key}, defines, library);
}

}  // namespace penumbra::gl

#endif
