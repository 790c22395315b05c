// Out of memory, said with the size asked for: the global operator new records the size of the
// allocation that failed before throwing std::bad_alloc, and main.cpp prints it. Left out under
// AddressSanitizer, which brings its own operator new.
#include <atomic>
#include <cstdlib>
#include <new>

#include "cli/Common.h"

namespace sl::cli {
std::atomic<size_t> gFailedAllocationBytes{0};
}

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SL_NO_OPERATOR_NEW 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define SL_NO_OPERATOR_NEW 1
#endif

#ifndef SL_NO_OPERATOR_NEW
// The replacements pair malloc with free; GCC's check for mismatched pairs sees only the
// standard operators' names.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t n) {
    if (void* p = std::malloc(n ? n : 1)) return p;
    sl::cli::gFailedAllocationBytes.store(n, std::memory_order_relaxed);
    throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
    return ::operator new(n);
}
void operator delete(void* p) noexcept {
    std::free(p);
}
void operator delete[](void* p) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
    std::free(p);
}
#endif
