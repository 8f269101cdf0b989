#pragma once
// Whether this test binary is built with AddressSanitizer (the sanitizer build, PCR_SANITIZE):
// tests that take minutes there run smaller or skip.

namespace pcr::test {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

}  // namespace pcr::test
