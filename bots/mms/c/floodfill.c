/* A flood-fill mouse written for the mms micromouse simulator, in C.
 *
 * It speaks mms's text commands (one a line on stdout, the answer read from stdin), so
 * it runs unchanged in mms and in mazearena (bot.toml: protocol = "mms"). It explores
 * towards the centre, flooding distances over the walls it knows (unknown ones taken as
 * open); at the centre it asks for the reset (`ackReset`), which puts it back at the
 * start; then it races the shortest path through the walls it has seen, several cells
 * at once on straight stretches. It logs to stderr and paints the cells it visits. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX 32
enum { NORTH, EAST, SOUTH, WEST };
static const int DX[4] = {0, 1, 0, -1}, DY[4] = {1, 0, -1, 0};

static int width, height, x, y, heading;
/* known[x][y] and wall[x][y]: bit d set when side d is known, or a wall */
static unsigned char known[MAX][MAX], wall[MAX][MAX];
static int dist[MAX][MAX];

static void ask(const char *command, char *answer, size_t size) {
    printf("%s\n", command);
    fflush(stdout);
    if (!fgets(answer, (int)size, stdin)) exit(0); /* the simulator is done with us */
    answer[strcspn(answer, "\r\n")] = 0;
}

static int ask_true(const char *command) {
    char answer[32];
    ask(command, answer, sizeof answer);
    return strcmp(answer, "true") == 0;
}

static int inside(int cx, int cy) { return cx >= 0 && cy >= 0 && cx < width && cy < height; }

static void set_wall(int cx, int cy, int d, int is_wall) {
    int nx = cx + DX[d], ny = cy + DY[d], back = (d + 2) % 4;
    known[cx][cy] |= 1 << d;
    if (is_wall) wall[cx][cy] |= 1 << d; else wall[cx][cy] &= ~(1 << d);
    if (inside(nx, ny)) {
        known[nx][ny] |= 1 << back;
        if (is_wall) wall[nx][ny] |= 1 << back; else wall[nx][ny] &= ~(1 << back);
    }
}

/* Whether side d of (cx, cy) may be crossed: open, or unknown when `optimistic`. */
static int passable(int cx, int cy, int d, int optimistic) {
    if (!(known[cx][cy] & (1 << d))) return optimistic;
    return !(wall[cx][cy] & (1 << d));
}

static int is_goal(int cx, int cy) {
    return (cx == width / 2 - 1 || cx == width / 2) && (cy == height / 2 - 1 || cy == height / 2);
}

static void flood(int optimistic) {
    static int queue[MAX * MAX][2];
    int head = 0, tail = 0;
    for (int i = 0; i < width; i++)
        for (int j = 0; j < height; j++) {
            dist[i][j] = is_goal(i, j) ? 0 : -1;
            if (dist[i][j] == 0) { queue[tail][0] = i; queue[tail][1] = j; tail++; }
        }
    while (head < tail) {
        int cx = queue[head][0], cy = queue[head][1];
        head++;
        for (int d = 0; d < 4; d++) {
            int nx = cx + DX[d], ny = cy + DY[d];
            if (inside(nx, ny) && passable(cx, cy, d, optimistic) && dist[nx][ny] < 0) {
                dist[nx][ny] = dist[cx][cy] + 1;
                queue[tail][0] = nx; queue[tail][1] = ny; tail++;
            }
        }
    }
}

/* The open side leading downhill, straight ahead first. */
static int best_side(int optimistic) {
    static const int order[4] = {0, 3, 1, 2};
    int best = -1, best_dist = 1 << 30;
    for (int k = 0; k < 4; k++) {
        int d = (heading + order[k]) % 4, nx = x + DX[d], ny = y + DY[d];
        if (!inside(nx, ny) || !passable(x, y, d, optimistic) || dist[nx][ny] < 0) continue;
        if (dist[nx][ny] < best_dist) { best = d; best_dist = dist[nx][ny]; }
    }
    return best;
}

static void face(int d) {
    int turn = (d - heading + 4) % 4;
    char answer[32];
    if (turn == 1) ask("turnRight", answer, sizeof answer);
    if (turn == 3) ask("turnLeft", answer, sizeof answer);
    if (turn == 2) { ask("turnRight", answer, sizeof answer); ask("turnRight", answer, sizeof answer); }
    heading = d;
}

static void forward(int cells) {
    char command[32], answer[32];
    snprintf(command, sizeof command, cells > 1 ? "moveForward %d" : "moveForward", cells);
    ask(command, answer, sizeof answer);
    if (strcmp(answer, "ack") != 0) {
        fprintf(stderr, "crashed at (%d, %d)\n", x, y);
        exit(1);
    }
    x += DX[heading] * cells;
    y += DY[heading] * cells;
}

int main(void) {
    char answer[32];
    ask("mazeWidth", answer, sizeof answer);
    width = atoi(answer);
    ask("mazeHeight", answer, sizeof answer);
    height = atoi(answer);
    if (width < 2 || height < 2 || width > MAX || height > MAX) return 2;
    for (int i = 0; i < width; i++) { set_wall(i, 0, SOUTH, 1); set_wall(i, height - 1, NORTH, 1); }
    for (int j = 0; j < height; j++) { set_wall(0, j, WEST, 1); set_wall(width - 1, j, EAST, 1); }
    fprintf(stderr, "maze %dx%d\n", width, height);
    while (!is_goal(x, y)) {
        set_wall(x, y, (heading + 3) % 4, ask_true("wallLeft"));
        set_wall(x, y, heading, ask_true("wallFront"));
        set_wall(x, y, (heading + 1) % 4, ask_true("wallRight"));
        printf("setColor %d %d c\n", x, y);
        flood(1);
        face(best_side(1));
        forward(1);
    }
    fprintf(stderr, "at the centre (%d, %d): reset\n", x, y);
    ask("ackReset", answer, sizeof answer);
    x = 0, y = 0, heading = NORTH;
    flood(0);
    while (!is_goal(x, y)) {
        int d = best_side(0), cells = 0, cx = x, cy = y;
        face(d);
        while (!is_goal(cx, cy) && passable(cx, cy, d, 0) && dist[cx + DX[d]][cy + DY[d]] == dist[cx][cy] - 1) {
            cx += DX[d], cy += DY[d], cells++;
        }
        forward(cells > 0 ? cells : 1);
    }
    fprintf(stderr, "done\n");
    return 0;
}
