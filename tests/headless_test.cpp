// Headless GL contexts: the backend named by PENUMBRA_GL (ctest runs this once per backend)
// really gives a GL 4.5 core context with compute/geometry shaders, KHR_debug reaches the
// callback, and bad backend names are refused.
#include <penumbra/gl/headless.hpp>

#include <doctest/doctest.h>

#include <atomic>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

using penumbra::gl::Backend;
using penumbra::gl::HeadlessContext;
using penumbra::gl::HeadlessOptions;

TEST_CASE("context on the requested backend") {
    std::vector<penumbra::gl::DebugMessage> messages;
    HeadlessOptions options;
    options.on_debug = [&](const penumbra::gl::DebugMessage& m) { messages.push_back(m); };
    HeadlessContext context(options);
    const char* env = std::getenv("PENUMBRA_GL");
    MESSAGE("backend=", std::string(penumbra::gl::backendName(context.backend())), " platform=", context.platform(),
            " renderer=", context.renderer(), " version=", context.version());
    if (env && std::string(env) == "osmesa") CHECK(context.backend() == Backend::OsMesa);
    if (env && std::string(env) == "egl") CHECK(context.backend() == Backend::Egl);
    CHECK(penumbra::gl::getInteger(GL_MAJOR_VERSION) * 10 + penumbra::gl::getInteger(GL_MINOR_VERSION) >= 45);
    CHECK((penumbra::gl::getInteger(GL_CONTEXT_PROFILE_MASK) & GL_CONTEXT_CORE_PROFILE_BIT) != 0);
    CHECK(!context.renderer().empty());
    CHECK(penumbra::gl::getInteger(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 0) >= 65535);
    CHECK(penumbra::gl::getInteger(GL_MAX_GEOMETRY_OUTPUT_VERTICES) >= 9);
    CHECK(penumbra::gl::getInteger(GL_MAX_DRAW_BUFFERS) >= 8);

    // KHR_debug: an application message must reach our callback.
    messages.clear();
    glDebugMessageInsert(GL_DEBUG_SOURCE_APPLICATION, GL_DEBUG_TYPE_MARKER, 4242, GL_DEBUG_SEVERITY_NOTIFICATION, -1,
                         "penumbra debug probe");
    bool seen = false;
    for (const auto& m : messages) seen = seen || (m.id == 4242 && m.text == "penumbra debug probe");
    CHECK(seen);
    // A GL error produces a message too (Mesa reports API errors through KHR_debug).
    messages.clear();
    glBindBuffer(0x1234, 0);
    CHECK(glGetError() == GL_INVALID_ENUM);
    CHECK(!messages.empty());
    CHECK_NOTHROW(penumbra::gl::checkErrors("after draining the error queue"));
}

TEST_CASE("contexts can be moved and recreated") {
    HeadlessContext a;
    HeadlessContext b(std::move(a));
    b.makeCurrent();
    CHECK(glGetString(GL_VERSION) != nullptr);
    b = HeadlessContext();
    CHECK(glGetString(GL_VERSION) != nullptr);
}

TEST_CASE("contexts created and destroyed on several threads at once (shared EGL display count)") {
    // Each thread owns its context (one current context per thread). The EGL display users are
    // counted under a lock: a racing count could terminate the display under a live context.
    HeadlessContext main_context;  // keeps the display alive across the rounds, like a test's context()
    std::atomic<int> failures{0};
    for (int round = 0; round < 3; ++round) {
        std::vector<std::thread> threads;
        for (int t = 0; t < 3; ++t) {
            threads.emplace_back([&failures] {
                try {
                    HeadlessContext context;
                    if (!glGetString(GL_VERSION)) ++failures;
                } catch (...) {
                    ++failures;
                }
            });
        }
        for (auto& thread : threads) thread.join();
    }
    CHECK(failures.load() == 0);
    main_context.makeCurrent();
    CHECK(glGetString(GL_VERSION) != nullptr);
}

TEST_CASE("an unknown PENUMBRA_GL value is an error, not a silent default") {
    const char* old = std::getenv("PENUMBRA_GL");
    std::string saved = old ? old : "";
    setenv("PENUMBRA_GL", "vulkan", 1);
    CHECK_THROWS_WITH_AS(HeadlessContext(), doctest::Contains("vulkan"), penumbra::Error);
    if (old) setenv("PENUMBRA_GL", saved.c_str(), 1); else unsetenv("PENUMBRA_GL");
}

TEST_CASE("PENUMBRA_EGL_DEVICE picks one listed EGL device; an index past the list is an error naming it") {
    const char* backend = std::getenv("PENUMBRA_GL");
    if (backend && std::string(backend) == "osmesa") {
        MESSAGE("skipped: PENUMBRA_EGL_DEVICE applies to the EGL backend only");
        return;
    }
    const char* old = std::getenv("PENUMBRA_EGL_DEVICE");
    const std::string saved = old ? old : "";
    setenv("PENUMBRA_EGL_DEVICE", "99", 1);
    HeadlessOptions egl;
    egl.backend = Backend::Egl;
    CHECK_THROWS_WITH_AS(HeadlessContext(egl), doctest::Contains("PENUMBRA_EGL_DEVICE=99"), penumbra::Error);
    setenv("PENUMBRA_EGL_DEVICE", "0", 1);  // Mesa lists its software device, NVIDIA its GPUs: index 0 exists
    try {
        HeadlessContext context(egl);
        MESSAGE("PENUMBRA_EGL_DEVICE=0: platform ", context.platform(), ", renderer ", context.renderer());
        CHECK(context.platform().rfind("egl-device", 0) == 0);
    } catch (const penumbra::Error& e) {
        // A device may be listed but give no 4.5 core context (e.g. Mesa's DRM-less device list):
        // then the message must say so, never fall back to another device.
        MESSAGE("PENUMBRA_EGL_DEVICE=0 gave no context: ", e.what());
        CHECK(std::string(e.what()).find("egl-device") != std::string::npos);
    }
    if (old) setenv("PENUMBRA_EGL_DEVICE", saved.c_str(), 1); else unsetenv("PENUMBRA_EGL_DEVICE");
}
