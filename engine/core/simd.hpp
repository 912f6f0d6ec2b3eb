#pragma once
/// @file simd.hpp
/// @brief The vectorised paths' shared declarations. The pair loops are written once with
/// Google Highway and compiled for several x86 instruction sets (AVX-512, AVX2 and a
/// portable fallback); the widest the CPU supports is chosen at run time (dynamic dispatch),
/// so a portable build still uses AVX-512 where it exists. Float builds only.
#include <string>

namespace sph {

/// @brief The instruction set the vectorised loops dispatch to on this machine
/// ("AVX3" is AVX-512, "AVX2", "EMU128" the portable fallback; "scalar" under SPH_DOUBLE).
std::string simd_target();

}  // namespace sph
