// Loops built twice, for the baseline x86-64 instruction set and for AVX2
// (with FMA where a build asks for it), the faster chosen at run time: the
// EKF's measurement and update (pose_ekf.cpp, ekf_measurement.cpp) and the
// detector's candidate-stage pixel loops (detector_half_image.cpp,
// detector_edge_map.cpp). Internal to vision.
//
// VISION_INLINE_ALL marks the function that holds one build: GCC then
// compiles everything it calls into it, for its instruction set (Clang
// inlines them without being asked). VISION_AVX2 and VISION_AVX2_FMA are
// defined only where the compiler can target those sets (x86-64).
#pragma once

#if defined(__GNUC__) && !defined(__clang__)
#define VISION_INLINE_ALL __attribute__((flatten))
#else
#define VISION_INLINE_ALL
#endif
#if defined(__x86_64__)
#define VISION_AVX2 __attribute__((target("avx2"))) VISION_INLINE_ALL
#define VISION_AVX2_FMA __attribute__((target("avx2,fma"))) VISION_INLINE_ALL
#endif

namespace vision::detail {

// Whether this CPU runs AVX2, and AVX2 with FMA (false off x86-64). Checked
// once per process.
bool cpu_has_avx2();
bool cpu_has_avx2_fma();

}  // namespace vision::detail
