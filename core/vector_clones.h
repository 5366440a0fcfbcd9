// HOVS_VECTOR_CLONES marks a hot loop function to be compiled three times, for AVX-512 (x86-64-v4: F, BW, CD,
// DQ, VL; DQ gives 64-bit multiplies to the hashes of the sample positions), AVX2 and baseline x86-64, with the
// copy chosen once at load time for the CPU it runs on (GCC's target_clones). Only plain loops over arrays
// benefit: the compiler vectorises them 8 or 4 doubles wide instead of 2.
//
// Reproducibility: no copy uses fused multiply-add (the AVX2 copy has no FMA target; x86-64-v4 implies FMA, so the
// files holding such functions are compiled with -ffp-contract=off), and additions, multiplications, divisions,
// square roots and conversions round the same in every copy, so a function marked with it returns bit-identical
// results on every x86-64 CPU. Do not call libm functions other than sqrt from such a function (their results
// may differ between builds of the library).
//
// The file holding such a function is compiled with -fno-math-errno -fno-trapping-math -ffp-contract=off (see
// the folder's CMakeLists.txt): without the first two, sqrt and branches over arithmetic stop the vectoriser;
// none of the three changes a result.
//
// Under AddressSanitizer, or on other architectures, it expands to nothing (one plain copy), and
// HOVS_VECTOR_CLONES_ENABLED is not defined (code that picks an x86-64-v4 function itself tests it).
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_ADDRESS__)
#define HOVS_VECTOR_CLONES __attribute__((target_clones("arch=x86-64-v4", "avx2", "default")))
#define HOVS_VECTOR_CLONES_ENABLED 1
#else
#define HOVS_VECTOR_CLONES
#endif
