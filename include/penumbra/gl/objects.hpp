// penumbra — small RAII owners for the GL objects penumbra's own helpers, tests and benchmarks
// create (buffers, textures, timer queries, executors' stage timers). Blocks never force these on
// an engine: block APIs take raw GLuint names the caller owns; these classes are a convenience for
// callers that have no wrapper of their own.
//
// needs: a current GL 4.5 context (DSA entry points); PENUMBRA_GL_HEADER (see gl.hpp).
#ifndef PENUMBRA_GL_OBJECTS_HPP
#define PENUMBRA_GL_OBJECTS_HPP

#include "penumbra/gl/gl.hpp"

#include <chrono>
#include <cstdint>
#include <utility>
#include <vector>

namespace penumbra::gl {

/// An owned, immutable-storage buffer object (glNamedBufferStorage).
class Buffer {
public:
    Buffer() = default;
    /// Allocates `bytes` (0 allowed: no GL object is created). `data` may be null.
    explicit Buffer(size_t bytes, const void* data = nullptr,
                    GLbitfield flags = GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT | GL_MAP_WRITE_BIT)
        : size_(bytes) {
        if (bytes == 0) return;
        PENUMBRA_CHECK(bytes <= static_cast<size_t>(PTRDIFF_MAX), "penumbra: buffer size ", bytes, " is too large");
        glCreateBuffers(1, &id_);
        while (glGetError() != GL_NO_ERROR) {
        }
        glNamedBufferStorage(id_, static_cast<GLsizeiptr>(bytes), data, flags);
        GLenum error = glGetError();
        if (error != GL_NO_ERROR) {
            glDeleteBuffers(1, &id_);
            id_ = 0;
            ::penumbra::detail::fail("penumbra: allocating a ", bytes, "-byte buffer failed with ", errorName(error));
        }
    }
    template <typename T>
    static Buffer fromVector(const std::vector<T>& values,
                             GLbitfield flags = GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT | GL_MAP_WRITE_BIT) {
        return Buffer(values.size() * sizeof(T), values.empty() ? nullptr : values.data(), flags);
    }
    Buffer(Buffer&& other) noexcept : id_(std::exchange(other.id_, 0)), size_(std::exchange(other.size_, 0)) {}
    Buffer& operator=(Buffer&& other) noexcept {
        if (this != &other) {
            reset();
            id_ = std::exchange(other.id_, 0);
            size_ = std::exchange(other.size_, 0);
        }
        return *this;
    }
    Buffer(const Buffer&) = delete;
    Buffer& operator=(const Buffer&) = delete;
    ~Buffer() { reset(); }

    GLuint id() const { return id_; }
    size_t size() const { return size_; }

    void upload(size_t offset, const void* data, size_t bytes) {
        PENUMBRA_CHECK(offset + bytes <= size_ && offset <= size_, "penumbra: upload of ", bytes, " bytes at ", offset,
                       " exceeds the ", size_, "-byte buffer");
        if (bytes) glNamedBufferSubData(id_, static_cast<GLintptr>(offset), static_cast<GLsizeiptr>(bytes), data);
    }
    /// Reads `count` elements of T starting at byte `offset`.
    template <typename T>
    std::vector<T> download(size_t offset = 0, size_t count = SIZE_MAX) const {
        if (count == SIZE_MAX) count = (size_ - offset) / sizeof(T);
        PENUMBRA_CHECK(offset <= size_ && count * sizeof(T) <= size_ - offset, "penumbra: download of ", count,
                       " elements at ", offset, " exceeds the ", size_, "-byte buffer");
        std::vector<T> out(count);
        if (count) {
            glGetNamedBufferSubData(id_, static_cast<GLintptr>(offset), static_cast<GLsizeiptr>(count * sizeof(T)),
                                    out.data());
        }
        return out;
    }
    /// Fills the whole buffer with a 32-bit pattern (poisoning before a test, clearing counters).
    void fill(uint32_t pattern) {
        if (id_) glClearNamedBufferData(id_, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &pattern);
    }
    void reset() {
        if (id_) deleteBuffers(1, &id_);  // keeps the engine's generic bindings (gl.hpp)
        id_ = 0;
        size_ = 0;
    }

private:
    GLuint id_ = 0;
    size_t size_ = 0;
};

/// An owned texture name (glCreateTextures); storage is the caller's business.
class Texture {
public:
    Texture() = default;
    explicit Texture(GLenum target) { glCreateTextures(target, 1, &id_); }
    Texture(Texture&& other) noexcept : id_(std::exchange(other.id_, 0)) {}
    Texture& operator=(Texture&& other) noexcept {
        if (this != &other) {
            reset();
            id_ = std::exchange(other.id_, 0);
        }
        return *this;
    }
    Texture(const Texture&) = delete;
    Texture& operator=(const Texture&) = delete;
    ~Texture() { reset(); }
    GLuint id() const { return id_; }
    void reset() {
        if (id_) glDeleteTextures(1, &id_);
        id_ = 0;
    }

private:
    GLuint id_ = 0;
};

/// An owned GL name of one kind (framebuffers, renderbuffers, vertex arrays, queries, samplers):
/// movable RAII.
template <void (*Create)(GLsizei, GLuint*), void (*Delete)(GLsizei, const GLuint*)>
class Name {
public:
    Name() = default;
    static Name create() {
        Name n;
        Create(1, &n.id_);
        return n;
    }
    Name(Name&& other) noexcept : id_(std::exchange(other.id_, 0)) {}
    Name& operator=(Name&& other) noexcept {
        if (this != &other) {
            reset();
            id_ = std::exchange(other.id_, 0);
        }
        return *this;
    }
    Name(const Name&) = delete;
    Name& operator=(const Name&) = delete;
    ~Name() { reset(); }
    GLuint id() const { return id_; }
    void reset() {
        if (id_) Delete(1, &id_);
        id_ = 0;
    }

private:
    GLuint id_ = 0;
};

namespace detail {
inline void createFramebuffers(GLsizei n, GLuint* ids) { glCreateFramebuffers(n, ids); }
inline void deleteFramebuffers(GLsizei n, const GLuint* ids) { glDeleteFramebuffers(n, ids); }
inline void createVertexArrays(GLsizei n, GLuint* ids) { glCreateVertexArrays(n, ids); }
inline void deleteVertexArrays(GLsizei n, const GLuint* ids) { glDeleteVertexArrays(n, ids); }
inline void createOcclusionQueries(GLsizei n, GLuint* ids) { glCreateQueries(GL_ANY_SAMPLES_PASSED, n, ids); }
inline void deleteQueries(GLsizei n, const GLuint* ids) { glDeleteQueries(n, ids); }
inline void createSamplers(GLsizei n, GLuint* ids) { glCreateSamplers(n, ids); }
inline void createRenderbuffers(GLsizei n, GLuint* ids) { glCreateRenderbuffers(n, ids); }
inline void deleteRenderbuffers(GLsizei n, const GLuint* ids) { glDeleteRenderbuffers(n, ids); }
inline void deleteSamplers(GLsizei n, const GLuint* ids) { glDeleteSamplers(n, ids); }
}  // namespace detail

using Framebuffer = Name<detail::createFramebuffers, detail::deleteFramebuffers>;
using VertexArray = Name<detail::createVertexArrays, detail::deleteVertexArrays>;
using OcclusionQuery = Name<detail::createOcclusionQueries, detail::deleteQueries>;
using Sampler = Name<detail::createSamplers, detail::deleteSamplers>;
using Renderbuffer = Name<detail::createRenderbuffers, detail::deleteRenderbuffers>;

/// GPU time of a region via GL_TIME_ELAPSED (nanoseconds). Regions must not nest.
class GpuTimer {
public:
    GpuTimer() { glCreateQueries(GL_TIME_ELAPSED, 1, &id_); }
    GpuTimer(GpuTimer&& other) noexcept : id_(std::exchange(other.id_, 0)) {}
    GpuTimer& operator=(GpuTimer&&) = delete;
    GpuTimer(const GpuTimer&) = delete;
    GpuTimer& operator=(const GpuTimer&) = delete;
    ~GpuTimer() {
        if (id_) glDeleteQueries(1, &id_);
    }
    void begin() { glBeginQuery(GL_TIME_ELAPSED, id_); }
    void end() { glEndQuery(GL_TIME_ELAPSED); }
    /// Blocks until the result is available.
    uint64_t nanoseconds() const {
        GLuint64 ns = 0;
        glGetQueryObjectui64v(id_, GL_QUERY_RESULT, &ns);
        return ns;
    }

private:
    GLuint id_ = 0;
};

/// An executor's optional per-stage timers (a tool's setting, never an engine's): off until
/// enable(); then begin(i) / end() bracket stage i < N with a GL_TIME_ELAPSED query or, with
/// wall_clock (drivers whose queries do not measure durations, e.g. llvmpipe), with glFinish + the
/// wall clock, which synchronises the frame. Stages must not nest; a stage not run keeps its last
/// time. While off, begin() and end() do nothing.
template <int N>
class StageTimers {
public:
    StageTimers() = default;
    StageTimers(const StageTimers&) = delete;
    StageTimers& operator=(const StageTimers&) = delete;
    ~StageTimers() {
        if (queries_[0]) glDeleteQueries(N, queries_);
    }
    void enable(bool wall_clock) {
        if (!queries_[0]) glCreateQueries(GL_TIME_ELAPSED, N, queries_);
        wall_clock_ = wall_clock;
    }
    bool enabled() const { return queries_[0] != 0; }
    void begin(int i) {
        if (!queries_[0]) return;
        stage_ = i;
        if (wall_clock_) {
            glFinish();
            start_ = std::chrono::steady_clock::now();
        } else {
            glBeginQuery(GL_TIME_ELAPSED, queries_[i]);
        }
    }
    void end() {
        if (!queries_[0]) return;
        if (wall_clock_) {
            glFinish();
            wall_ms_[stage_] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
        } else {
            glEndQuery(GL_TIME_ELAPSED);
        }
    }
    /// Stage i's last time in milliseconds (waits for the GPU); 0 while off.
    double milliseconds(int i) const {
        if (!queries_[0]) return 0.0;
        if (wall_clock_) return wall_ms_[i];
        GLuint64 ns = 0;
        glGetQueryObjectui64v(queries_[i], GL_QUERY_RESULT, &ns);
        return double(ns) * 1e-6;
    }

private:
    GLuint queries_[N] = {};
    bool wall_clock_ = false;
    int stage_ = 0;
    double wall_ms_[N] = {};
    std::chrono::steady_clock::time_point start_{};
};

}  // namespace penumbra::gl

#endif
