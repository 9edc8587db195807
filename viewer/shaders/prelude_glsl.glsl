// GLSL spelling of the macros that let the shared headers compile as C++ too
// (Bruneton's model.cc prepends the same definitions; src/glsl_cpp.h has the C++ ones).
#define Number float
#define IN(x) in x
#define OUT(x) out x
#define INOUT(x) inout x
