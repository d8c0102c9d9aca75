/* spot_member_begin.h: include before a shared GLSL source (one written for both sides: see
 * spot_shared.h) inside a C++ class body, and spot_member_end.h after it. The source's functions
 * become member functions, its constants static members, and its out/inout parameters references,
 * so the class supplies the accessors the source calls (the buffers it reads on the GPU).
 * No include guard: a file includes it once per class. */
#define SPOT_FN
#define SPOT_CONST static constexpr
#define SPOT_OUT(T) T&
#define SPOT_INOUT(T) T&
