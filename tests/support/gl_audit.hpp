// GL call recorder for per-frame contract tests (issue 7 "Must show": after warm-up, scan(),
// build() and run() make 0 queries, 0 glGetError, 0 maps/read-backs/glFinish/fence waits).
//
// Needs glad's debug loader: the executable links penumbra_glad_debug instead of penumbra_glad
// (tests/CMakeLists.txt: `penumbra_add_test(NAME ... SOURCES ... GL GLAD_DEBUG)`, or GLAD_DEBUG on
// penumbra_add_block_test). With it every gl* macro goes through glad_debug_impl_gl*, which calls
// the pre-call callback with the function's name before the real entry point. Including this header
// installs penumbra's callbacks for the whole program (at static initialisation and again in every
// GlAudit constructor):
//   pre-call:  while a GlAudit is recording, appends the name (a string literal inside glad: no
//              copy, no allocation) to the audit's preallocated log; always reports a NULL entry
//              point on stderr, as glad's default does.
//   both:      mark the thread as inside a driver call (support/driver_call.hpp), so the
//              allocation counter can leave the driver's own operator new calls out.
//   post-call: nothing else. glad's DEFAULT pre- and post-callbacks both call glGetError after
//              every call: they would drain the engine's own errors (a test could then never see
//              the GL_INVALID_* an executor causes) and hide the executor's own glGetError. Ours
//              never call GL.
//
// Classification (by name; each call falls in at most one of the four groups):
//   read-backs: glGetBufferSubData, glGetNamedBufferSubData, glGet[n][Compressed]Tex[ture][Sub]Image,
//               glReadPixels, glReadnPixels, glGetQueryObject*
//   queries:    every other glGet*, glIs*, glCheck*Status (glGetError included; errorChecks()
//               counts it alone)
//   maps:       glMapBuffer, glMapBufferRange, glMapNamedBuffer, glMapNamedBufferRange
//   sync waits: glFinish, glClientWaitSync, glWaitSync
//
// How a block test uses it (with support/alloc_counter.hpp for the heap):
//
//     #include "support/alloc_counter.hpp"  // exactly one translation unit of the executable
//     #include "support/gl_audit.hpp"
//     ...
//     penumbra::Scanner scanner;                   // setup / reserve(): queries allowed here
//     scanner.scan(in, out, n);                    // warm-up: lazy driver compiles, first-use state
//     glFinish();
//     penumbra::test::GlAudit audit;               // allocates its log now, not while recording
//     penumbra::test::AllocationCounter heap;
//     audit.start();
//     heap.start();
//     scanner.scan(in, out, n);                    // the per-frame call under test (no CHECKs here:
//     heap.stop();                                 //  doctest allocates)
//     audit.stop();
//     INFO(audit.report());                        // every call, in order, and the counts
//     CHECK(audit.calls() > 0);                    // it did record something
//     CHECK(audit.queries() == 0);                 // no glGet*/glIs*/glCheck*Status
//     CHECK(audit.errorChecks() == 0);             // no glGetError (a subset of queries)
//     CHECK(audit.readBacks() == 0);
//     CHECK(audit.maps() == 0);
//     CHECK(audit.syncWaits() == 0);               // no glFinish / fence wait
//     CHECK(heap.allocations() == 0);
//
// Only one GlAudit records at a time (start() while another records throws std::logic_error).
// Calls from other threads are recorded too (GL is used from one thread in penumbra's tests).
#ifndef PENUMBRA_TESTS_SUPPORT_GL_AUDIT_HPP
#define PENUMBRA_TESTS_SUPPORT_GL_AUDIT_HPP

#include "penumbra/gl/gl.hpp"
#include "support/driver_call.hpp"

#ifndef GLAD_OPTION_GL_DEBUG
#error "support/gl_audit.hpp needs glad's debug loader: link penumbra_glad_debug (penumbra_add_test(... GL GLAD_DEBUG))"
#endif

#include <atomic>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace penumbra::test {

enum class GlCallKind { Other, Query, ReadBack, Map, SyncWait };

inline const char* glCallKindName(GlCallKind kind) {
    switch (kind) {
        case GlCallKind::Query: return "query";
        case GlCallKind::ReadBack: return "read-back";
        case GlCallKind::Map: return "map";
        case GlCallKind::SyncWait: return "sync wait";
        default: return "other";
    }
}

namespace detail {

inline bool startsWith(const char* s, const char* prefix) { return std::strncmp(s, prefix, std::strlen(prefix)) == 0; }

inline bool endsWith(const char* s, const char* suffix) {
    const size_t n = std::strlen(s), m = std::strlen(suffix);
    return n >= m && std::strcmp(s + n - m, suffix) == 0;
}

}  // namespace detail

/// The group of one GL function name (see the header comment).
inline GlCallKind classifyGlCall(const char* name) {
    using detail::endsWith;
    using detail::startsWith;
    if (!name || !startsWith(name, "gl")) return GlCallKind::Other;
    if (std::strcmp(name, "glGetBufferSubData") == 0 || std::strcmp(name, "glGetNamedBufferSubData") == 0 ||
        std::strcmp(name, "glReadPixels") == 0 || std::strcmp(name, "glReadnPixels") == 0 ||
        startsWith(name, "glGetQueryObject")) {
        return GlCallKind::ReadBack;
    }
    if (startsWith(name, "glGet") && endsWith(name, "Image")) {
        // glGet[n][Compressed]Tex[ture][Sub]Image
        const char* rest = name + 5;
        if (*rest == 'n') ++rest;
        if (startsWith(rest, "Compressed")) rest += 10;
        if (startsWith(rest, "Tex")) return GlCallKind::ReadBack;
    }
    if (startsWith(name, "glGet") || startsWith(name, "glIs") ||
        (startsWith(name, "glCheck") && endsWith(name, "Status"))) {
        return GlCallKind::Query;
    }
    if (std::strcmp(name, "glMapBuffer") == 0 || std::strcmp(name, "glMapBufferRange") == 0 ||
        std::strcmp(name, "glMapNamedBuffer") == 0 || std::strcmp(name, "glMapNamedBufferRange") == 0) {
        return GlCallKind::Map;
    }
    if (std::strcmp(name, "glFinish") == 0 || std::strcmp(name, "glClientWaitSync") == 0 ||
        std::strcmp(name, "glWaitSync") == 0) {
        return GlCallKind::SyncWait;
    }
    return GlCallKind::Other;
}

class GlAudit;

namespace detail {

inline std::atomic<GlAudit*>& recordingGlAudit() {
    static std::atomic<GlAudit*> audit{nullptr};
    return audit;
}

inline void glAuditRecord(GlAudit& audit, const char* name);

inline void glAuditPreCall(const char* name, GLADapiproc apiproc, int /*len_args*/, ...) {
    if (apiproc == nullptr) std::fprintf(stderr, "GLAD: ERROR %s is NULL!\n", name);
    if (GlAudit* audit = recordingGlAudit().load(std::memory_order_acquire)) glAuditRecord(*audit, name);
    enterDriverCall();
}

inline void glAuditPostCall(void* /*ret*/, const char* /*name*/, GLADapiproc /*apiproc*/, int /*len_args*/, ...) {
    leaveDriverCall();
}

inline bool installGlAuditCallbacks() {
    gladSetGLPreCallback(glAuditPreCall);
    gladSetGLPostCallback(glAuditPostCall);
    return true;
}

// Replaces glad's error-draining defaults before main() in every program that includes this.
inline const bool kGlAuditCallbacksInstalled = installGlAuditCallbacks();

}  // namespace detail

/// Records the names of the GL calls made between start() and stop() (see the header comment).
/// Recording itself neither allocates nor calls GL.
class GlAudit {
public:
    /// `capacity` names are kept (allocated here); calls beyond it are still counted (calls(),
    /// overflowed()) but classified only up to the capacity (report() says so).
    explicit GlAudit(size_t capacity = size_t(1) << 16) : log_(capacity, nullptr) { detail::installGlAuditCallbacks(); }
    GlAudit(const GlAudit&) = delete;
    GlAudit& operator=(const GlAudit&) = delete;
    ~GlAudit() { stop(); }

    /// Clears the log and records until stop(). Throws std::logic_error if another audit records.
    void start() {
        size_ = 0;
        total_ = 0;
        GlAudit* expected = nullptr;
        if (!detail::recordingGlAudit().compare_exchange_strong(expected, this) && expected != this) {
            throw std::logic_error("penumbra::test::GlAudit::start: another GlAudit is recording");
        }
    }
    void stop() {
        GlAudit* expected = this;
        detail::recordingGlAudit().compare_exchange_strong(expected, nullptr);
    }
    bool recording() const { return detail::recordingGlAudit().load() == this; }

    /// Every call recorded (overflow included).
    size_t calls() const { return total_; }
    bool overflowed() const { return total_ > size_; }
    /// The i-th recorded name (i < min(calls(), capacity)).
    const char* call(size_t i) const { return i < size_ ? log_[i] : nullptr; }
    /// The recorded names in call order (allocates: use after stop()).
    std::vector<std::string> names() const { return std::vector<std::string>(log_.begin(), log_.begin() + size_); }
    /// Calls of the graphics pipeline in the log (draws, queries, conditional rendering, stencil,
    /// framebuffer, viewport and vertex-array calls), each also reported as a doctest MESSAGE by
    /// the caller if it likes: the compute light passes must make none.
    std::vector<std::string> graphicsCalls() const {
        std::vector<std::string> out;
        for (const std::string& name : names())
            for (const char* word : {"Draw", "Query", "ConditionalRender", "Stencil", "Framebuffer", "Viewport", "VertexArray"})
                if (name.find(word) != std::string::npos) {
                    out.push_back(name);
                    break;
                }
        return out;
    }

    size_t count(GlCallKind kind) const {
        size_t n = 0;
        for (size_t i = 0; i < size_; ++i) n += classifyGlCall(log_[i]) == kind;
        return n;
    }
    /// Calls of exactly this function.
    size_t count(const char* name) const {
        size_t n = 0;
        for (size_t i = 0; i < size_; ++i) n += std::strcmp(log_[i], name) == 0;
        return n;
    }
    size_t queries() const { return count(GlCallKind::Query); }
    size_t errorChecks() const { return count("glGetError"); }
    size_t readBacks() const { return count(GlCallKind::ReadBack); }
    size_t maps() const { return count(GlCallKind::Map); }
    size_t syncWaits() const { return count(GlCallKind::SyncWait); }
    /// queries + read-backs + maps + sync waits: what a per-frame call must not make.
    size_t forbidden() const { return queries() + readBacks() + maps() + syncWaits(); }

    /// "N calls: Q queries (E glGetError), R read-backs, M maps, S sync waits", then every call in
    /// order with its group when it is not "other" (allocates: use after stop()).
    std::string report() const {
        std::string out = std::to_string(total_) + " GL calls: " + std::to_string(queries()) + " queries (" +
                          std::to_string(errorChecks()) + " glGetError), " + std::to_string(readBacks()) +
                          " read-backs, " + std::to_string(maps()) + " maps, " + std::to_string(syncWaits()) +
                          " sync waits";
        if (overflowed()) out += " (only the first " + std::to_string(size_) + " kept and classified)";
        out += "\n";
        for (size_t i = 0; i < size_; ++i) {
            out += "  " + std::to_string(i) + " " + log_[i];
            const GlCallKind kind = classifyGlCall(log_[i]);
            if (kind != GlCallKind::Other) out += std::string("  <- ") + glCallKindName(kind);
            out += "\n";
        }
        return out;
    }

private:
    friend void detail::glAuditRecord(GlAudit& audit, const char* name);
    std::vector<const char*> log_;
    size_t size_ = 0, total_ = 0;
};

namespace detail {

inline void glAuditRecord(GlAudit& audit, const char* name) {
    if (audit.size_ < audit.log_.size()) audit.log_[audit.size_++] = name;
    ++audit.total_;
}

}  // namespace detail

}  // namespace penumbra::test

#endif
