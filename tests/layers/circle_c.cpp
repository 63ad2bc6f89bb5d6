// circle_c.cpp - the circle's last file: C++ calling back into circle_a.c.
extern "C" int fl_circle_a(int n);
int circle_c(int n);

int circle_c(int n) { return n > 0 ? fl_circle_a(n - 1) : 0; }
