/// @file registry.h
/// @brief The registry's one list: a line per method, in the order `render --help` and the bench
/// list them. SPOT_METHOD(name) stands for `MethodInfo name##Method()`, which the method's module
/// defines (splat/methods/<name>/; its sources are found by splat/CMakeLists.txt). Adding a
/// method is its folder and its line here. Included by splat/method_vk.cpp only.
SPOT_METHOD(reference)
SPOT_METHOD(instanced)
SPOT_METHOD(oit)
SPOT_METHOD(hybrid)
SPOT_METHOD(sorted)
SPOT_METHOD(raymarch)
SPOT_METHOD(baked)
