/* spot_member_end.h: closes spot_member_begin.h (the macros it defined are undefined). */
#undef SPOT_FN
#undef SPOT_CONST
#undef SPOT_OUT
#undef SPOT_INOUT
