/* The cheapest possible protocol-v1 bot: answers every sense message with
 * {"rotation":0,"movement":0} and exits on the end message. Used to measure the
 * referee's own per-step overhead (the match always runs all 1000 steps). */
#include <stdio.h>
#include <string.h>

int main(void) {
    char line[70000];
    setvbuf(stdout, NULL, _IOLBF, 0);
    while (fgets(line, sizeof line, stdin)) {
        if (strstr(line, "\"type\":\"sense\"")) {
            fputs("{\"rotation\":0,\"movement\":0}\n", stdout);
        } else if (strstr(line, "\"type\":\"end\"")) {
            break;
        }
    }
    return 0;
}
