#pragma once
// PNP_SANITIZER_ALLOCATOR is defined when a sanitizer (ASan, TSan, MSan) owns malloc: then
// glibc's allocator settings and a replaced malloc must be left alone. GCC says so with
// __SANITIZE_*__, clang with __has_feature.

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define PNP_SANITIZER_ALLOCATOR 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer)
#define PNP_SANITIZER_ALLOCATOR 1
#endif
#endif

// PNP_SANITIZER_THREAD is defined under ThreadSanitizer (GCC or clang).
#if defined(__SANITIZE_THREAD__)
#define PNP_SANITIZER_THREAD 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define PNP_SANITIZER_THREAD 1
#endif
#endif
