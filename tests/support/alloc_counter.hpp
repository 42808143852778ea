// Counting allocator for per-frame contract tests ("a counting allocator: 0 heap allocations").
//
// Including this header REPLACES the global operator new and operator delete, every form
// (plain, array, nothrow, align_val_t, sized), for the whole executable: the replacements are
// ordinary (non-inline) definitions, as the standard requires, so include it in EXACTLY ONE
// translation unit of an executable (a second one fails to link with "multiple definition of
// operator new"). They allocate with std::malloc / std::aligned_alloc and free with std::free,
// follow the new_handler protocol and throw std::bad_alloc like the standard ones.
//
// penumbra::test::AllocationCounter counts operator new calls while it is started:
//   allocations() / bytes():   calls (and bytes asked for) made ON THE THREAD THAT CALLED start()
//                              — penumbra's executors run on the caller's thread; driver worker
//                              threads (llvmpipe) are not the executor's allocations;
//   allThreadsAllocations():   calls made on any thread while started;
//   deallocations():           operator delete calls of a non-null pointer on the starting thread.
//   driverAllocations():       calls on the starting thread made INSIDE a GL call (between glad's
//                              pre- and post-call callbacks of support/gl_audit.hpp, see
//                              support/driver_call.hpp): the driver's, not penumbra's. NVIDIA's
//                              driver allocates through the program's operator new in draws and
//                              dispatches; they are left out of allocations().
// malloc/free called directly (C code, the GL driver) are not seen. Counting neither allocates
// nor locks (a thread_local pointer and relaxed atomics). One counter per thread at a time.
//
// Usage (see support/gl_audit.hpp for the full per-frame test):
//     penumbra::test::AllocationCounter heap;
//     heap.start();
//     executor.run(...);   // no doctest macros in between: they allocate
//     heap.stop();
//     CHECK(heap.allocations() == 0);
#ifndef PENUMBRA_TESTS_SUPPORT_ALLOC_COUNTER_HPP
#define PENUMBRA_TESTS_SUPPORT_ALLOC_COUNTER_HPP

#include "support/driver_call.hpp"

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <stdexcept>

namespace penumbra::test {

class AllocationCounter;

namespace detail {

inline thread_local AllocationCounter* t_allocation_counter = nullptr;

inline std::atomic<int>& startedAllocationCounters() {
    static std::atomic<int> started{0};
    return started;
}

inline std::atomic<uint64_t>& allThreadsAllocationCount() {
    static std::atomic<uint64_t> count{0};
    return count;
}

inline void countAllocation(std::size_t bytes);
inline void countDeallocation(void* p);

}  // namespace detail

class AllocationCounter {
public:
    AllocationCounter() = default;
    AllocationCounter(const AllocationCounter&) = delete;
    AllocationCounter& operator=(const AllocationCounter&) = delete;
    ~AllocationCounter() { stop(); }

    /// Resets the counts and counts until stop(). Throws std::logic_error when another counter is
    /// started on this thread.
    void start() {
        if (detail::t_allocation_counter && detail::t_allocation_counter != this) {
            throw std::logic_error("penumbra::test::AllocationCounter::start: another counter is started on this thread");
        }
        allocations_ = deallocations_ = bytes_ = driver_allocations_ = 0;
        all_threads_base_ = detail::allThreadsAllocationCount().load();
        all_threads_ = 0;
        if (detail::t_allocation_counter != this) detail::startedAllocationCounters().fetch_add(1);
        detail::t_allocation_counter = this;
    }
    void stop() {
        if (detail::t_allocation_counter != this) return;
        detail::t_allocation_counter = nullptr;
        all_threads_ = detail::allThreadsAllocationCount().load() - all_threads_base_;
        detail::startedAllocationCounters().fetch_sub(1);
    }
    bool started() const { return detail::t_allocation_counter == this; }

    /// operator new calls on the starting thread while started, outside GL calls.
    uint64_t allocations() const { return allocations_; }
    /// operator new calls on the starting thread while started, inside GL calls (the driver's).
    uint64_t driverAllocations() const { return driver_allocations_; }
    /// Bytes those calls asked for.
    uint64_t bytes() const { return bytes_; }
    /// operator delete calls (non-null) on the starting thread while started.
    uint64_t deallocations() const { return deallocations_; }
    /// operator new calls on every thread while started (includes allocations()). Exact once
    /// stopped; while started it reads the running total.
    uint64_t allThreadsAllocations() const {
        return started() ? detail::allThreadsAllocationCount().load() - all_threads_base_ : all_threads_;
    }

private:
    friend void detail::countAllocation(std::size_t bytes);
    friend void detail::countDeallocation(void* p);
    uint64_t allocations_ = 0, deallocations_ = 0, bytes_ = 0, driver_allocations_ = 0;
    uint64_t all_threads_base_ = 0, all_threads_ = 0;
};

namespace detail {

inline void countAllocation(std::size_t bytes) {
    if (startedAllocationCounters().load(std::memory_order_relaxed) == 0) return;
    allThreadsAllocationCount().fetch_add(1, std::memory_order_relaxed);
    if (AllocationCounter* counter = t_allocation_counter) {
        if (insideDriverCall()) {
            ++counter->driver_allocations_;
            return;
        }
        ++counter->allocations_;
        counter->bytes_ += bytes;
    }
}

inline void countDeallocation(void* p) {
    if (!p || startedAllocationCounters().load(std::memory_order_relaxed) == 0) return;
    if (AllocationCounter* counter = t_allocation_counter) {
        if (!insideDriverCall()) ++counter->deallocations_;
    }
}

inline void* allocateOrThrow(std::size_t bytes, std::size_t alignment) {
    if (bytes == 0) bytes = 1;
    for (;;) {
        void* p = nullptr;
        if (alignment <= alignof(std::max_align_t)) {
            p = std::malloc(bytes);
        } else {
            // aligned_alloc wants a size that is a multiple of the alignment.
            const std::size_t rounded = (bytes + alignment - 1) / alignment * alignment;
            p = std::aligned_alloc(alignment, rounded);
        }
        if (p) {
            countAllocation(bytes);
            return p;
        }
        std::new_handler handler = std::get_new_handler();
        if (!handler) throw std::bad_alloc();
        handler();
    }
}

inline void* allocateOrNull(std::size_t bytes, std::size_t alignment) noexcept {
    try {
        return allocateOrThrow(bytes, alignment);
    } catch (...) {
        return nullptr;
    }
}

inline void release(void* p) noexcept {
    countDeallocation(p);
    std::free(p);
}

}  // namespace detail

}  // namespace penumbra::test

// ---- the replacements (one translation unit per executable) ------------------------------------
// clang-format off
void* operator new(std::size_t n) { return penumbra::test::detail::allocateOrThrow(n, 0); }
void* operator new[](std::size_t n) { return penumbra::test::detail::allocateOrThrow(n, 0); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return penumbra::test::detail::allocateOrNull(n, 0); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return penumbra::test::detail::allocateOrNull(n, 0); }
void* operator new(std::size_t n, std::align_val_t a) { return penumbra::test::detail::allocateOrThrow(n, static_cast<std::size_t>(a)); }
void* operator new[](std::size_t n, std::align_val_t a) { return penumbra::test::detail::allocateOrThrow(n, static_cast<std::size_t>(a)); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept { return penumbra::test::detail::allocateOrNull(n, static_cast<std::size_t>(a)); }
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept { return penumbra::test::detail::allocateOrNull(n, static_cast<std::size_t>(a)); }

void operator delete(void* p) noexcept { penumbra::test::detail::release(p); }
void operator delete[](void* p) noexcept { penumbra::test::detail::release(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { penumbra::test::detail::release(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { penumbra::test::detail::release(p); }
void operator delete(void* p, std::size_t) noexcept { penumbra::test::detail::release(p); }
void operator delete[](void* p, std::size_t) noexcept { penumbra::test::detail::release(p); }
void operator delete(void* p, std::align_val_t) noexcept { penumbra::test::detail::release(p); }
void operator delete[](void* p, std::align_val_t) noexcept { penumbra::test::detail::release(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { penumbra::test::detail::release(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { penumbra::test::detail::release(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { penumbra::test::detail::release(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { penumbra::test::detail::release(p); }
// clang-format on

#endif
