// Whether this build runs under AddressSanitizer (-DIQC_SANITIZE=ON): the few places that must behave
// differently there (a renderer that keeps Mesa's driver loaded, tests that cannot bound address space)
// ask this, nothing else.
#pragma once

namespace iqc {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSanitizerBuild = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kAddressSanitizerBuild = true;
#else
inline constexpr bool kAddressSanitizerBuild = false;
#endif
#else
inline constexpr bool kAddressSanitizerBuild = false;
#endif

}  // namespace iqc
