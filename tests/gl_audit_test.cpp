// The recorders the per-frame contract tests rely on (support/gl_audit.hpp, support/alloc_counter.hpp)
// record what they claim: a query, a glFinish and a read-back are seen and classified, a region of
// pure dispatch calls shows 0 forbidden calls, the audit does not drain the engine's GL errors, and
// the allocation counter sees a std::vector's allocation and 0 in an empty region. Linked with glad's
// debug loader (penumbra_glad_debug); ctest runs it on EGL and OSMesa.
#include "support/alloc_counter.hpp"  // the one translation unit of this executable that includes it
#include "support/gl_audit.hpp"
#include "support/gl_test_support.hpp"

#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/shader.hpp>

#include <doctest/doctest.h>

#include <memory>
#include <string>
#include <thread>
#include <vector>

using penumbra::test::classifyGlCall;
using penumbra::test::GlAudit;
using penumbra::test::GlCallKind;

TEST_CASE("GL call names are classified as the per-frame contract reads them") {
    for (const char* name : {"glGetIntegerv", "glGetError", "glIsBuffer", "glCheckFramebufferStatus",
                             "glCheckNamedFramebufferStatus", "glGetProgramiv", "glGetStringi",
                             "glGetQueryBufferObjecti64v", "glGetBufferParameteriv", "glGetTextureLevelParameteriv"}) {
        CAPTURE(name);
        CHECK(classifyGlCall(name) == GlCallKind::Query);
    }
    for (const char* name : {"glGetBufferSubData", "glGetNamedBufferSubData", "glGetTexImage", "glGetTextureImage",
                             "glGetTextureSubImage", "glGetCompressedTexImage", "glGetCompressedTextureImage",
                             "glGetnTexImage", "glGetnCompressedTexImage", "glReadPixels", "glReadnPixels",
                             "glGetQueryObjectuiv", "glGetQueryObjectui64v"}) {
        CAPTURE(name);
        CHECK(classifyGlCall(name) == GlCallKind::ReadBack);
    }
    for (const char* name : {"glMapBuffer", "glMapBufferRange", "glMapNamedBuffer", "glMapNamedBufferRange"}) {
        CAPTURE(name);
        CHECK(classifyGlCall(name) == GlCallKind::Map);
    }
    for (const char* name : {"glFinish", "glClientWaitSync", "glWaitSync"}) {
        CAPTURE(name);
        CHECK(classifyGlCall(name) == GlCallKind::SyncWait);
    }
    for (const char* name : {"glDispatchCompute", "glUseProgram", "glBindBufferRange", "glMemoryBarrier", "glFlush",
                             "glFenceSync", "glUnmapBuffer", "glDrawArrays", "glBeginQuery", "glGenerateMipmap"}) {
        CAPTURE(name);
        CHECK(classifyGlCall(name) == GlCallKind::Other);
    }
}

TEST_CASE("the GL audit sees a query, a glFinish and a read-back, and nothing outside start/stop") {
    penumbra::test::context();
    GlAudit audit;
    GLint value = 0;
    glGetIntegerv(GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS, &value);  // before start: not recorded
    audit.start();
    CHECK(audit.recording());
    glGetIntegerv(GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS, &value);
    glFinish();
    audit.stop();
    glFinish();  // after stop: not recorded
    INFO(audit.report());
    CHECK(value > 0);
    CHECK(!audit.recording());
    CHECK(audit.calls() == 2);
    CHECK(audit.count("glGetIntegerv") == 1);
    CHECK(audit.queries() == 1);
    CHECK(audit.syncWaits() == 1);
    CHECK(audit.count("glFinish") == 1);
    CHECK(audit.errorChecks() == 0);
    CHECK(audit.readBacks() == 0);
    CHECK(audit.maps() == 0);
    CHECK(audit.forbidden() == 2);
    REQUIRE(audit.names().size() == 2);
    CHECK(audit.names()[0] == "glGetIntegerv");
    CHECK(audit.names()[1] == "glFinish");

    // A read-back, a map and an explicit glGetError.
    penumbra::gl::Buffer buffer(64);
    audit.start();
    uint32_t word = 0;
    glGetNamedBufferSubData(buffer.id(), 0, 4, &word);
    void* mapped = glMapNamedBufferRange(buffer.id(), 0, 4, GL_MAP_READ_BIT);
    glUnmapNamedBuffer(buffer.id());
    const GLenum error = glGetError();
    audit.stop();
    INFO(audit.report());
    CHECK(mapped != nullptr);
    CHECK(error == GL_NO_ERROR);
    CHECK(audit.calls() == 4);
    CHECK(audit.readBacks() == 1);
    CHECK(audit.maps() == 1);
    CHECK(audit.errorChecks() == 1);
    CHECK(audit.queries() == 1);  // the glGetError
    CHECK(audit.syncWaits() == 0);

    // start() clears the previous log; a second recorder cannot start while one records.
    audit.start();
    GlAudit other(16);
    CHECK_THROWS_AS(other.start(), std::logic_error);
    audit.stop();
    CHECK(audit.calls() == 0);
}

TEST_CASE("a region of pure dispatch calls records every call and 0 forbidden ones") {
    penumbra::test::context();
    penumbra::gl::Program copy = penumbra::gl::buildComputeProgram("penumbra/common/copy.comp.glsl");
    std::vector<uint32_t> data(1024);
    for (size_t i = 0; i < data.size(); ++i) data[i] = static_cast<uint32_t>(i * 2654435761u);
    auto src = penumbra::gl::Buffer::fromVector(data);
    penumbra::gl::Buffer dst(data.size() * 4);
    GlAudit audit;
    audit.start();
    glUseProgram(copy.id());
    glUniform1ui(0, static_cast<GLuint>(data.size() / 4));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, src.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, dst.id());
    glDispatchCompute(1, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    audit.stop();
    INFO(audit.report());
    CHECK(audit.calls() == 6);
    CHECK(audit.count("glDispatchCompute") == 1);
    CHECK(audit.count("glBindBufferBase") == 2);
    CHECK(audit.queries() == 0);
    CHECK(audit.errorChecks() == 0);
    CHECK(audit.readBacks() == 0);
    CHECK(audit.maps() == 0);
    CHECK(audit.syncWaits() == 0);
    CHECK(audit.forbidden() == 0);
    CHECK(!audit.overflowed());
    // The dispatch really ran (read back outside the recorded region).
    CHECK(dst.download<uint32_t>() == data);
}

TEST_CASE("the audit's callbacks do not drain the engine's GL errors") {
    penumbra::test::context();
    while (glGetError() != GL_NO_ERROR) {
    }
    GlAudit audit;
    audit.start();
    glBindBuffer(0x1234, 0);  // GL_INVALID_ENUM (KHR_debug prints it: expected)
    glUseProgram(0);
    audit.stop();
    CHECK(audit.calls() == 2);
    CHECK(audit.errorChecks() == 0);
    // glad's default callbacks call glGetError around every call: the error would be gone here.
    CHECK(glGetError() == GL_INVALID_ENUM);
    CHECK(glGetError() == GL_NO_ERROR);
}

TEST_CASE("the log overflows gracefully: calls are still counted") {
    penumbra::test::context();
    GlAudit audit(4);
    audit.start();
    for (int i = 0; i < 10; ++i) glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    audit.stop();
    CHECK(audit.calls() == 10);
    CHECK(audit.overflowed());
    CHECK(audit.names().size() == 4);
    CHECK(audit.report().find("only the first 4") != std::string::npos);
}

TEST_CASE("the allocation counter sees a std::vector's allocation and 0 in an empty region") {
    penumbra::test::AllocationCounter heap;
    heap.start();
    heap.stop();
    CHECK(heap.allocations() == 0);
    CHECK(heap.bytes() == 0);
    CHECK(heap.allThreadsAllocations() == 0);

    heap.start();
    {
        std::vector<double> v(1000);
        v[999] = 1.0;
    }
    heap.stop();
    CHECK(heap.allocations() == 1);
    CHECK(heap.bytes() == 1000 * sizeof(double));
    CHECK(heap.deallocations() == 1);
    CHECK(heap.allThreadsAllocations() >= 1);

    // Every form goes through the counter: array, nothrow, over-aligned, sized delete.
    struct alignas(64) Wide {
        float lanes[16];
    };
    heap.start();
    int* array = new int[7];
    delete[] array;
    int* nothrow = new (std::nothrow) int(3);
    delete nothrow;
    auto wide = std::make_unique<Wide>();
    const bool aligned = reinterpret_cast<uintptr_t>(wide.get()) % 64 == 0;
    wide.reset();
    Wide* wide_array = new Wide[3];
    delete[] wide_array;
    heap.stop();
    CHECK(aligned);
    CHECK(heap.allocations() == 4);
    CHECK(heap.deallocations() == 4);

    // Allocations outside start/stop are not counted.
    std::vector<int> outside(10);
    CHECK(heap.allocations() == 4);

    // Another thread's allocations: not the caller's, but seen by allThreadsAllocations().
    std::thread worker;  // constructed before start: launching it allocates its state
    heap.start();
    worker = std::thread([] {
        std::vector<int> v(100);
        v[0] = 1;
    });
    worker.join();
    heap.stop();
    CHECK(heap.allocations() >= 1);  // std::thread's own state, allocated by the starting thread
    CHECK(heap.allThreadsAllocations() >= 2);

    penumbra::test::AllocationCounter second;
    heap.start();
    CHECK_THROWS_AS(second.start(), std::logic_error);
    heap.stop();
}

TEST_CASE("allocations inside a GL call are the driver's: counted apart, not as the caller's") {
    penumbra::test::context();
    namespace detail = penumbra::test::detail;
    penumbra::test::AllocationCounter heap;
    heap.start();
    detail::enterDriverCall();  // what glad's pre-call callback does (support/gl_audit.hpp)
    int* in_driver = new int(1);
    delete in_driver;
    detail::leaveDriverCall();
    int* ours = new int(2);
    delete ours;
    heap.stop();
    CHECK(heap.allocations() == 1);
    CHECK(heap.deallocations() == 1);
    CHECK(heap.driverAllocations() == 1);
    // Real GL calls go through the callbacks: after them the thread is outside the driver again.
    CHECK_FALSE(detail::insideDriverCall());
    GLuint buffer = 0;
    glCreateBuffers(1, &buffer);
    glNamedBufferData(buffer, 64, nullptr, GL_DYNAMIC_DRAW);
    glDeleteBuffers(1, &buffer);
    CHECK_FALSE(detail::insideDriverCall());
    CHECK(detail::t_driver_call_depth == 0);
}
