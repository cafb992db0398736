/* CPU-bound work with no I/O, for the machine's own scaling floor: a walk over a small
 * table (cache-resident, like a bot's maze search) for N steps. Prints nothing; its
 * wall time is taken by the caller.
 *
 *   spin N      (N steps; about 1 s for N = 300000000 on the project's machine) */
#include <stdint.h>
#include <stdlib.h>

static volatile uint32_t sink;

int main(int argc, char **argv) {
    long n = argc > 1 ? atol(argv[1]) : 300000000L;
    static uint32_t table[1 << 16];
    for (uint32_t i = 0; i < (1u << 16); i++) table[i] = i * 2654435761u;
    uint32_t x = 1;
    for (long i = 0; i < n; i++) {
        x = table[x & 0xffff] ^ (x >> 3) ^ (uint32_t)i;
        table[(x >> 7) & 0xffff] += x;
    }
    sink = x + table[x & 0xffff];
    return 0;
}
