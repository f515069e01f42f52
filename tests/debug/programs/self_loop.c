/* Ends in a jump to itself, as idle loops do. */
volatile int ready;

int main(void) {
    ready = 1;
    for (;;) {
    }
}
