/* circle_a.c - a third of a circle of files (a -> b -> c -> a), which the
 * test layers_no_cycles_detects must find: C calling C++ through a C name. */
int fl_circle_b(int n);
int fl_circle_a(int n);

int fl_circle_a(int n) { return n > 0 ? fl_circle_b(n - 1) : 0; }
