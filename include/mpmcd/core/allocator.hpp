#pragma once
/// How the C library's allocator keeps the memory of large blocks (glibc malloc), set for the
/// buffers that the contact solve allocates and frees at every Newton iteration (docs/parallel.md,
/// "Page faults of large buffers").

namespace mpmcd {

/// Blocks up to this size come from the heap and are reused after they are freed, instead of
/// being mapped anew (and page-faulted in, page by page) at every allocation [bytes]; glibc's
/// largest allowed value (32 MiB on 64-bit systems).
inline constexpr int kMmapThreshold = 32 << 20;
/// Free memory at the top of the heap kept for reuse rather than returned to the system [bytes].
inline constexpr int kTrimThreshold = 1 << 30;

/// Called first in main: sets kMmapThreshold and kTrimThreshold (glibc mallopt) unless the user
/// tuned malloc through GLIBC_TUNABLES; does nothing with another C library.
void apply_allocator_policy();

}  // namespace mpmcd
