// Ends the region nn/target_begin.h opened. No include guard (see there).

#if defined(__clang__)
#pragma clang attribute pop
#elif defined(__GNUC__)
#pragma GCC pop_options
#endif
#undef PNP_TARGET
