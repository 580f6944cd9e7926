#pragma once
// FLATSOS_UNDER_ASAN is defined in AddressSanitizer builds (GCC and Clang spell it differently):
// there ASan owns malloc and keeps freed memory in quarantine.
#if defined(__SANITIZE_ADDRESS__)  // GCC
#define FLATSOS_UNDER_ASAN 1
#elif defined(__has_feature)  // Clang
#if __has_feature(address_sanitizer)
#define FLATSOS_UNDER_ASAN 1
#endif
#endif
