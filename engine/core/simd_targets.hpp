#pragma once
// Included first by every Highway translation unit (before hwy/foreach_target.h): the
// targets compiled. AVX-512 (AVX3) and AVX2 cover the machines this engine runs on; SSE4/SSSE3
// would add compile time for CPUs older than 2013, which get the portable EMU128 code instead.
#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS (HWY_SSSE3 | HWY_SSE4 | HWY_AVX3_DL)
#endif
