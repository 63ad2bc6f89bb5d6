// circle_b.cpp - the circle's second file: a C entry calling C++ by its
// mangled name, which the test must match raw (no demangling).
int circle_c(int n);
extern "C" int fl_circle_b(int n);

extern "C" int fl_circle_b(int n) { return n > 0 ? circle_c(n - 1) : 0; }
