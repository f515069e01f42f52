/* The single-core debugging test program: a function to break in, a global to print, one to watch. */
#include "hf_print.h"

volatile int counter;
int total = 5;

int __attribute__((noinline)) work(int n) {
    int s = 0;
    for (int i = 0; i < n; i++) s += i * 3;
    counter = s;
    return s;
}

int main(void) {
    hf_printf("start\n");
    int r = 0;
    for (int k = 0; k < 3; k++) r += work(10 + k);
    total = r;
    hf_printf("total %d\n", r);
    return 7;
}
