/* Runs until stopped from outside: for Ctrl-C and kill. */
volatile unsigned counter;

int main(void) {
    for (;;) counter++;
}
