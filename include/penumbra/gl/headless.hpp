// penumbra — headless OpenGL 4.5 core contexts for tests, benchmarks, examples and offline tools.
//
// Integration summary
//   needs:    libEGL (link it; CMake target penumbra::headless does), libdl; OSMesa is optional and
//             loaded at run time with dlopen (libOSMesa.so.8): GL/osmesa.h declares GL itself and
//             clashes with loader headers such as glad's, so we declare the five entry points we
//             use ourselves and a machine without OSMesa still runs the EGL backend.
//   produces: a current GL 4.5 core context on the calling thread, GL entry points loaded through
//             the PENUMBRA_GL_LOAD hook (default: glad 2's gladLoadGL), KHR_debug messages routed
//             to a callback, renderer/version strings.
//   hooks:    PENUMBRA_GL_HEADER (see gl.hpp); PENUMBRA_GL_LOAD(get_proc) — an expression that
//             loads GL through `get_proc` (type penumbra::gl::ProcLoader) and yields nonzero on
//             success; define both for an engine loader other than glad.
//
// Backend choice: Backend::Auto reads the environment variable PENUMBRA_GL (`egl` or `osmesa`);
// unset means EGL, falling back to OSMesa when no EGL display gives a 4.5 core context. An
// explicit backend (argument or environment) never falls back: tests labelled for a backend must
// really run on it. EGL tries EGL_EXT_platform_device hardware devices first (NVIDIA's driver
// offers no surfaceless platform), then Mesa's surfaceless platform, then software devices;
// PENUMBRA_EGL_DEVICE=i picks the i-th listed device alone (several GPUs; glvnd's
// __EGL_VENDOR_LIBRARY_FILENAMES picks the vendor library).
#ifndef PENUMBRA_GL_HEADLESS_HPP
#define PENUMBRA_GL_HEADLESS_HPP

#include "penumbra/gl/gl.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <map>
#include <mutex>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace penumbra::gl {

using ProcLoader = void (*(*)(const char*))();

}  // namespace penumbra::gl

#ifndef PENUMBRA_GL_LOAD
#define PENUMBRA_GL_LOAD(get_proc) gladLoadGL(reinterpret_cast<GLADloadfunc>(get_proc))
#endif

namespace penumbra::gl {

enum class Backend { Auto, Egl, OsMesa };

inline const char* backendName(Backend backend) {
    switch (backend) {
        case Backend::Egl: return "egl";
        case Backend::OsMesa: return "osmesa";
        default: return "auto";
    }
}

/// One KHR_debug message as delivered to the callback.
struct DebugMessage {
    GLenum source = 0;
    GLenum type = 0;
    GLuint id = 0;
    GLenum severity = 0;
    std::string text;
};

using DebugCallback = std::function<void(const DebugMessage&)>;

/// Value-initialised = defaults.
struct HeadlessOptions {
    Backend backend = Backend::Auto;  ///< Auto: environment PENUMBRA_GL, else EGL then OSMesa
    bool debug = true;                ///< debug context + KHR_debug output to `on_debug`
    DebugCallback on_debug;           ///< empty: print high/medium severity messages to stderr. Called
                                      ///< on the thread making the GL call (GL_DEBUG_OUTPUT_SYNCHRONOUS
                                      ///< is enabled), so a callback touching only this context's
                                      ///< thread's data needs no lock
};

namespace detail {

// OSMesa entry points, declared here instead of including GL/osmesa.h (see the summary).
struct OsMesaApi {
    using Context = void*;
    using CreateContextAttribs = Context (*)(const int*, Context);
    using DestroyContext = void (*)(Context);
    using MakeCurrent = unsigned char (*)(Context, void*, GLenum, GLsizei, GLsizei);
    using GetProcAddress = void (*(*)(const char*))();
    enum : int {
        kFormat = 0x22,
        kDepthBits = 0x30,
        kStencilBits = 0x31,
        kAccumBits = 0x32,
        kProfile = 0x33,
        kCoreProfile = 0x34,
        kMajorVersion = 0x36,
        kMinorVersion = 0x37,
    };
    void* library = nullptr;
    CreateContextAttribs create_context_attribs = nullptr;
    DestroyContext destroy_context = nullptr;
    MakeCurrent make_current = nullptr;
    GetProcAddress get_proc_address = nullptr;

    static OsMesaApi& instance() {
        static OsMesaApi api = load();
        return api;
    }

private:
    static OsMesaApi load() {
        OsMesaApi api;
        for (const char* name : {"libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so"}) {
            api.library = dlopen(name, RTLD_NOW | RTLD_LOCAL);
            if (api.library) break;
        }
        if (!api.library) return api;
        api.create_context_attribs =
            reinterpret_cast<CreateContextAttribs>(dlsym(api.library, "OSMesaCreateContextAttribs"));
        api.destroy_context = reinterpret_cast<DestroyContext>(dlsym(api.library, "OSMesaDestroyContext"));
        api.make_current = reinterpret_cast<MakeCurrent>(dlsym(api.library, "OSMesaMakeCurrent"));
        api.get_proc_address = reinterpret_cast<GetProcAddress>(dlsym(api.library, "OSMesaGetProcAddress"));
        return api;
    }
};

inline thread_local OsMesaApi::GetProcAddress tls_osmesa_get_proc = nullptr;

// eglGetPlatformDisplayEXT returns the same EGLDisplay for the same platform, and eglTerminate
// would destroy every context on it, so displays are reference-counted across HeadlessContexts.
// Contexts may be created and destroyed on different threads (one context per thread): the count
// is read and written only under the mutex, and the terminate decision is taken under it too.
// (It used to hand out a reference to the map entry and count outside the lock: a data race.)
struct EglDisplayUsers {
    std::mutex mutex;
    std::map<EGLDisplay, int> users;

    static EglDisplayUsers& instance() {
        static EglDisplayUsers registry;
        return registry;
    }
};

/// eglInitialize + one more user, atomically with respect to releaseEglDisplay (EGL itself does not
/// count: an eglTerminate between another thread's eglInitialize and its count would kill the
/// display under it).
inline bool initializeEglDisplay(EGLDisplay display, EGLint* major, EGLint* minor) {
    EglDisplayUsers& registry = EglDisplayUsers::instance();
    std::lock_guard<std::mutex> lock(registry.mutex);
    if (!eglInitialize(display, major, minor)) return false;
    ++registry.users[display];
    return true;
}

/// Terminates the display when its last user releases it (under the lock, so a concurrent
/// acquire either sees the display alive or initialises it again after the terminate).
inline void releaseEglDisplay(EGLDisplay display) {
    EglDisplayUsers& registry = EglDisplayUsers::instance();
    std::lock_guard<std::mutex> lock(registry.mutex);
    int& users = registry.users[display];
    if (--users <= 0) {
        registry.users.erase(display);
        eglTerminate(display);
    }
}

inline void (*osMesaProc(const char* name))() { return tls_osmesa_get_proc(name); }

inline void (*eglProc(const char* name))() { return eglGetProcAddress(name); }

inline void GLAPIENTRY debugTrampoline(GLenum source, GLenum type, GLuint id, GLenum severity,
                                       GLsizei length, const GLchar* message, const void* user) {
    const auto* callback = static_cast<const DebugCallback*>(user);
    DebugMessage msg{source, type, id, severity,
                     length >= 0 ? std::string(message, static_cast<size_t>(length)) : std::string(message)};
    (*callback)(msg);
}

inline void defaultDebugPrinter(const DebugMessage& msg) {
    if (msg.severity == GL_DEBUG_SEVERITY_HIGH || msg.severity == GL_DEBUG_SEVERITY_MEDIUM) {
        std::fprintf(stderr, "penumbra GL debug [id %u, severity 0x%x]: %s\n", msg.id, msg.severity,
                     msg.text.c_str());
    }
}

inline Backend backendFromEnvironment() {
    const char* env = std::getenv("PENUMBRA_GL");
    if (!env || !*env) return Backend::Auto;
    if (std::strcmp(env, "egl") == 0) return Backend::Egl;
    if (std::strcmp(env, "osmesa") == 0) return Backend::OsMesa;
    ::penumbra::detail::fail("penumbra: PENUMBRA_GL='", env, "' is not a backend (use egl or osmesa)");
}

}  // namespace detail

/// A current GL 4.5 core context owned by this object (RAII, movable, not copyable). The context
/// is made current on the constructing thread; use it from that thread.
class HeadlessContext {
public:
    explicit HeadlessContext(const HeadlessOptions& options = {}) : state_(std::make_unique<State>()) {
        state_->on_debug = options.on_debug ? options.on_debug : DebugCallback(detail::defaultDebugPrinter);
        Backend wanted = options.backend;
        if (wanted == Backend::Auto) wanted = detail::backendFromEnvironment();
        std::string egl_error;
        if (wanted == Backend::Egl || wanted == Backend::Auto) {
            egl_error = createEgl(options.debug);
            if (egl_error.empty()) {
                finish(options.debug);
                return;
            }
            PENUMBRA_CHECK(wanted == Backend::Auto, "penumbra: EGL context failed: ", egl_error);
        }
        std::string osmesa_error = createOsMesa(options.debug);
        PENUMBRA_CHECK(osmesa_error.empty(), "penumbra: OSMesa context failed: ", osmesa_error,
                       egl_error.empty() ? std::string() : "; EGL before it: " + egl_error);
        finish(options.debug);
    }

    HeadlessContext(HeadlessContext&&) noexcept = default;
    HeadlessContext& operator=(HeadlessContext&& other) noexcept {
        if (this != &other) {
            destroy();
            state_ = std::move(other.state_);
        }
        return *this;
    }
    HeadlessContext(const HeadlessContext&) = delete;
    HeadlessContext& operator=(const HeadlessContext&) = delete;
    ~HeadlessContext() { destroy(); }

    Backend backend() const { return state_->backend; }
    const std::string& renderer() const { return state_->renderer; }
    /// Whether the renderer runs on the CPU (Mesa's llvmpipe or softpipe, OpenSWR). There the
    /// finished wall time is the execution time, and GL_TIME_ELAPSED is no measurement: llvmpipe
    /// 22 starts a query's clock when its rasteriser executes the scene holding it, while compute
    /// dispatches run at once on the calling thread, so compute work issued before the first
    /// flush after glBeginQuery is left out (a shadow-edge stencil run read 49 ms on the query
    /// against 136 ms of wall time).
    bool cpuRenderer() const {
        const std::string& r = state_->renderer;
        return r.find("llvmpipe") != std::string::npos || r.find("softpipe") != std::string::npos ||
               r.find("SWR") != std::string::npos;
    }
    const std::string& version() const { return state_->version; }
    /// e.g. "egl-surfaceless", "egl-device", "osmesa".
    const std::string& platform() const { return state_->platform; }
    bool hasExtension(const char* name) const {
        GLint count = getInteger(GL_NUM_EXTENSIONS);
        for (GLint i = 0; i < count; ++i) {
            const char* ext = reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, static_cast<GLuint>(i)));
            if (ext && std::strcmp(ext, name) == 0) return true;
        }
        return false;
    }
    /// Makes the context current again on the calling thread.
    void makeCurrent() {
        if (state_->backend == Backend::Egl) {
            eglMakeCurrent(state_->egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, state_->egl_context);
        } else {
            auto& api = detail::OsMesaApi::instance();
            api.make_current(state_->osmesa_context, state_->osmesa_buffer.data(), GL_UNSIGNED_BYTE, 4, 4);
            detail::tls_osmesa_get_proc = api.get_proc_address;
        }
    }

private:
    struct State {
        Backend backend = Backend::Auto;
        std::string platform, renderer, version;
        EGLDisplay egl_display = EGL_NO_DISPLAY;
        EGLContext egl_context = EGL_NO_CONTEXT;
        void* osmesa_context = nullptr;
        std::vector<unsigned char> osmesa_buffer;
        DebugCallback on_debug;  // lives here so its address stays put across moves
    };
    std::unique_ptr<State> state_;

    static std::string eglErrorText(const char* what) {
        char buffer[96];
        std::snprintf(buffer, sizeof buffer, "%s (EGL error 0x%x)", what, static_cast<unsigned>(eglGetError()));
        return buffer;
    }

    // Returns "" on success, else why the display could not give a 4.5 core context.
    std::string tryEglDisplay(EGLDisplay display, bool debug) {
        if (display == EGL_NO_DISPLAY) return "no display";
        EGLint major = 0, minor = 0;
        if (!detail::initializeEglDisplay(display, &major, &minor)) return eglErrorText("eglInitialize failed");
        const char* extensions = eglQueryString(display, EGL_EXTENSIONS);
        std::string ext = extensions ? extensions : "";
        if (ext.find("EGL_KHR_surfaceless_context") == std::string::npos) {
            detail::releaseEglDisplay(display);
            return "display lacks EGL_KHR_surfaceless_context";
        }
        if (!eglBindAPI(EGL_OPENGL_API)) {
            detail::releaseEglDisplay(display);
            return eglErrorText("eglBindAPI(EGL_OPENGL_API) failed");
        }
        EGLConfig config = nullptr;
        if (ext.find("EGL_KHR_no_config_context") == std::string::npos) {
            const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
            EGLint count = 0;
            if (!eglChooseConfig(display, config_attribs, &config, 1, &count) || count < 1) {
                detail::releaseEglDisplay(display);
                return eglErrorText("no EGL config with EGL_OPENGL_BIT");
            }
        }
        const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4,
                                          EGL_CONTEXT_MINOR_VERSION, 5,
                                          EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                          EGL_CONTEXT_OPENGL_DEBUG, debug ? EGL_TRUE : EGL_FALSE,
                                          EGL_NONE};
        EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attribs);
        if (context == EGL_NO_CONTEXT) {
            std::string why = eglErrorText("eglCreateContext(4.5 core) failed");
            detail::releaseEglDisplay(display);
            return why;
        }
        if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
            std::string why = eglErrorText("eglMakeCurrent(surfaceless) failed");
            eglDestroyContext(display, context);
            detail::releaseEglDisplay(display);
            return why;
        }
        state_->egl_display = display;
        state_->egl_context = context;
        state_->backend = Backend::Egl;
        return {};
    }

    std::string createEgl(bool debug) {
        // glad's EGL loader finds no EGL 1.5 entry points before a display exists; the EXT entry
        // points through eglGetProcAddress work on every EGL we target.
        auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
            eglGetProcAddress("eglGetPlatformDisplayEXT"));
        auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
        auto query_device_string =
            reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(eglGetProcAddress("eglQueryDeviceStringEXT"));
        if (!get_platform_display) return "eglGetPlatformDisplayEXT is not available";
        std::string errors;
        std::vector<EGLDeviceEXT> hardware, software;
        if (query_devices) {
            EGLDeviceEXT devices[16];
            EGLint count = 0;
            if (query_devices(16, devices, &count)) {
                for (EGLint i = 0; i < count; ++i) {
                    const char* ext = query_device_string ? query_device_string(devices[i], EGL_EXTENSIONS) : nullptr;
                    bool is_software = ext && std::strstr(ext, "EGL_MESA_device_software");
                    (is_software ? software : hardware).push_back(devices[i]);
                }
            }
        }
        auto attempt = [&](EGLenum platform, void* native, const char* name) {
            std::string why = tryEglDisplay(get_platform_display(platform, native, nullptr), debug);
            if (why.empty()) {
                state_->platform = name;
                return true;
            }
            errors += std::string(errors.empty() ? "" : "; ") + name + ": " + why;
            return false;
        };
        // PENUMBRA_EGL_DEVICE=i: only the i-th device eglQueryDevicesEXT lists (hardware or
        // software), for machines with several GPUs; no fallback to another device or platform.
        if (const char* pick = std::getenv("PENUMBRA_EGL_DEVICE"); pick && *pick) {
            char* end = nullptr;
            const long index = std::strtol(pick, &end, 10);
            std::vector<EGLDeviceEXT> all;
            if (query_devices) {
                EGLDeviceEXT devices[16];
                EGLint count = 0;
                if (query_devices(16, devices, &count)) all.assign(devices, devices + count);
            }
            if (*end != '\0' || index < 0 || static_cast<size_t>(index) >= all.size()) {
                return "PENUMBRA_EGL_DEVICE=" + std::string(pick) + " names no EGL device (" + std::to_string(all.size()) +
                       " listed)";
            }
            const bool is_software = std::find(software.begin(), software.end(), all[size_t(index)]) != software.end();
            if (attempt(EGL_PLATFORM_DEVICE_EXT, all[size_t(index)], is_software ? "egl-device-software" : "egl-device")) return {};
            return errors;
        }
        for (EGLDeviceEXT device : hardware) {
            if (attempt(EGL_PLATFORM_DEVICE_EXT, device, "egl-device")) return {};
        }
        if (attempt(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, "egl-surfaceless")) return {};
        for (EGLDeviceEXT device : software) {
            if (attempt(EGL_PLATFORM_DEVICE_EXT, device, "egl-device-software")) return {};
        }
        return errors.empty() ? "no EGL platform available" : errors;
    }

    std::string createOsMesa(bool /*debug: OSMesa has no debug-context attribute*/) {
        auto& api = detail::OsMesaApi::instance();
        if (!api.library) return "libOSMesa.so could not be loaded (install libosmesa6)";
        if (!api.create_context_attribs || !api.make_current || !api.get_proc_address || !api.destroy_context) {
            return "libOSMesa lacks OSMesaCreateContextAttribs (need Mesa >= 11.2)";
        }
        const int attribs[] = {OsMesaApi::kFormat, GL_RGBA, OsMesaApi::kDepthBits, 24, OsMesaApi::kStencilBits, 8,
                               OsMesaApi::kAccumBits, 0, OsMesaApi::kProfile, OsMesaApi::kCoreProfile,
                               OsMesaApi::kMajorVersion, 4, OsMesaApi::kMinorVersion, 5, 0};
        void* context = api.create_context_attribs(attribs, nullptr);
        if (!context) return "OSMesaCreateContextAttribs(4.5 core) failed";
        // OSMesa insists on a colour buffer; rendering goes to framebuffer objects anyway.
        state_->osmesa_buffer.assign(4 * 4 * 4, 0);
        if (!api.make_current(context, state_->osmesa_buffer.data(), GL_UNSIGNED_BYTE, 4, 4)) {
            api.destroy_context(context);
            return "OSMesaMakeCurrent failed";
        }
        state_->osmesa_context = context;
        state_->backend = Backend::OsMesa;
        state_->platform = "osmesa";
        return {};
    }

    using OsMesaApi = detail::OsMesaApi;

    void finish(bool debug) {
        ProcLoader loader = detail::eglProc;
        if (state_->backend == Backend::OsMesa) {
            detail::tls_osmesa_get_proc = detail::OsMesaApi::instance().get_proc_address;
            loader = detail::osMesaProc;
        }
        int loaded = PENUMBRA_GL_LOAD(loader);
        if (!loaded) {
            std::string where = state_->platform;
            destroy();
            ::penumbra::detail::fail("penumbra: loading GL 4.5 entry points failed on ", where);
        }
        const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
        const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
        state_->renderer = renderer ? renderer : "";
        state_->version = version ? version : "";
        GLint major = getInteger(GL_MAJOR_VERSION), minor = getInteger(GL_MINOR_VERSION);
        if (major * 10 + minor < 45) {
            std::string got = state_->version;
            destroy();
            ::penumbra::detail::fail("penumbra: need OpenGL 4.5 core, the driver gave ", got);
        }
        if (debug) {
            glEnable(GL_DEBUG_OUTPUT);
            glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
            glDebugMessageCallback(detail::debugTrampoline, &state_->on_debug);
            glDebugMessageControl(GL_DONT_CARE, GL_DONT_CARE, GL_DONT_CARE, 0, nullptr, GL_TRUE);
        }
        while (glGetError() != GL_NO_ERROR) {
        }
    }

    void destroy() {
        if (!state_) return;
        if (state_->egl_context != EGL_NO_CONTEXT) {
            // Only unbind when this context is the current one: another live context may be.
            if (eglGetCurrentContext() == state_->egl_context) {
                eglMakeCurrent(state_->egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
            }
            eglDestroyContext(state_->egl_display, state_->egl_context);
            detail::releaseEglDisplay(state_->egl_display);
            state_->egl_context = EGL_NO_CONTEXT;
        }
        if (state_->osmesa_context) {
            detail::OsMesaApi::instance().destroy_context(state_->osmesa_context);
            state_->osmesa_context = nullptr;
        }
        state_.reset();
    }
};

}  // namespace penumbra::gl

#endif
