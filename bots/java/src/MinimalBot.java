import mazebot.Answer;
import mazebot.Bot;
import mazebot.Debug;
import mazebot.EndInfo;
import mazebot.MazeBot;
import mazebot.MazeMap;
import mazebot.Pose;
import mazebot.StartInfo;

/**
 * A small, deterministic reference bot for mazearena, in Java: the twin of
 * {@code bots/c/minimal_bot.c} (and of {@code bots/python/simple_bot.py}). The protocol
 * is in {@link MazeBot}, the wall map in {@link MazeMap}.
 *
 * <h2>Strategy</h2>
 *
 * <p><b>Wall map.</b> Every edge between two cells is unknown, open or wall (the outer
 * perimeter starts as wall). A sensor reading d in a direction reveals the edges along
 * that ray: d open edges, then a wall.
 *
 * <p><b>Run 0 (exploration).</b> Flood fill from the goal room over every edge not known
 * to be a wall (unknown counts as open), so each cell gets an optimistic distance to the
 * goal. Each step the bot heads to a neighbour one closer, preferring straight ahead,
 * then left, right, back, and moves up to 3 cells while the cells keep getting closer and
 * the edges are known open (so it never hits a wall and always knows where it is). It
 * re-plans every step. After a step that ended in the goal room it answers reset.
 *
 * <p><b>Run 1 (timed run).</b> Breadth-first search over (cell, heading) using only edges
 * known to be open (unknown = wall): one step is one rotation (-90, 0, 90) followed by a
 * straight move of -3..3 cells, exactly the game's move. The bot follows the shortest such
 * plan, re-planned every step.
 *
 * <p>If the goal cannot be reached (the map proves it walled off), the bot turns on the
 * spot until the step limit: it never crashes and never hits a wall.
 *
 * <p><b>Debug drawing.</b> Each answer carries a {@link Debug} for the replay viewer (the
 * flood-fill distances as a grid, the way down them to the goal as a path, a line of
 * text, and the walls it knows whenever it learnt a new one). It changes nothing in the
 * moves.
 */
public final class MinimalBot implements Bot {

    private static final int INF = 0x3fffffff;
    /** Larger mazes: the bot only turns on the spot. */
    private static final int MAX_DIM = 1024;
    /** Straight, left, right, back (relative turns, in quarter turns clockwise). */
    private static final int[] ORDER = {0, 3, 1, 2};
    private static final int[] ROTATIONS = {0, -90, 90};
    private static final int[] MOVEMENTS = {3, 2, 1, -1, -2, -3, 0};

    private MazeMap map;          // null: unusable maze, only safe moves
    private int[] dist;           // flood fill, per cell
    private int[] queue;          // BFS queue: n * n * 4 entries
    private int[] parent;         // run-1 BFS: parent state, -1 for the start, -2 unvisited
    private byte[] act;           // run-1 BFS: (rotation index, movement) that led to a state
    private int[] path;           // debug drawing: x, y of each cell of the path
    private final Pose pose = new Pose();
    private final Debug debug = new Debug();
    private int run;
    private boolean enteredGoal;
    private boolean flooded;      // dist holds this step's flood fill (run 0)
    private int wallsDrawn = -1;  // walls in the last drawing that listed them

    /** A bot waiting for its start message. */
    public MinimalBot() {
    }

    // --- run 0: flood fill, unknown = open ------------------------------------------

    private void flood() {
        int n = map.size();
        int head = 0;
        int tail = 0;
        int lo = map.goalLo();
        java.util.Arrays.fill(dist, INF);
        for (int gx = lo; gx <= lo + 1; gx++) {
            for (int gy = lo; gy <= lo + 1; gy++) {
                if (map.inside(gx, gy)) {
                    dist[map.cell(gx, gy)] = 0;
                    queue[tail++] = map.cell(gx, gy);
                }
            }
        }
        while (head < tail) {
            int c = queue[head++];
            int x = c / n;
            int y = c % n;
            for (int d = 0; d < 4; d++) {
                int nx = x + MazeMap.dx(d);
                int ny = y + MazeMap.dy(d);
                if (map.edge(x, y, d) == MazeMap.WALL || !map.inside(nx, ny)) {
                    continue;
                }
                if (dist[map.cell(nx, ny)] == INF) {
                    dist[map.cell(nx, ny)] = dist[c] + 1;
                    queue[tail++] = map.cell(nx, ny);
                }
            }
        }
    }

    private Answer exploreMove() {
        flood();
        flooded = true;
        int here = dist[map.cell(pose.x, pose.y)];
        if (here == INF) {
            return Answer.move(90, 0); // the goal is walled off: turn on the spot
        }
        int rel = -1;
        int d = 0;
        for (int turn : ORDER) {
            int dd = (pose.heading + turn) & 3;
            int nx = pose.x + MazeMap.dx(dd);
            int ny = pose.y + MazeMap.dy(dd);
            if (map.edge(pose.x, pose.y, dd) != MazeMap.WALL && map.inside(nx, ny)
                    && dist[map.cell(nx, ny)] == here - 1) {
                rel = turn;
                d = dd;
                break;
            }
        }
        if (rel < 0) { // in the goal room without having entered it (n = 2): step out
            for (int dd = 0; dd < 4 && rel < 0; dd++) {
                if (map.edge(pose.x, pose.y, dd) == MazeMap.OPEN) {
                    rel = (dd - pose.heading + 4) & 3;
                    d = dd;
                }
            }
            if (rel < 0) {
                return Answer.move(90, 0); // look around
            }
        }
        if (map.edge(pose.x, pose.y, d) != MazeMap.OPEN) {
            return Answer.move(90, 0); // the edge behind is unsensed: turn to look at it
        }
        int rotation = rel == 1 ? 90 : rel == 3 ? -90 : 0;
        int sign = rel == 2 ? -1 : 1;
        int cells = 0;
        int x = pose.x;
        int y = pose.y;
        while (cells < 3 && map.edge(x, y, d) == MazeMap.OPEN) {
            int nx = x + MazeMap.dx(d);
            int ny = y + MazeMap.dy(d);
            if (cells > 0 && dist[map.cell(nx, ny)] != dist[map.cell(x, y)] - 1) {
                break;
            }
            x = nx;
            y = ny;
            cells++;
            if (map.inGoal(x, y)) {
                break;
            }
        }
        return Answer.move(rotation, sign * cells);
    }

    // --- run 1: BFS over (cell, heading), unknown = wall ------------------------------

    /** The first move of a shortest known plan to the goal room, or null if none. */
    private Answer planMove() {
        int n = map.size();
        int states = n * n * 4;
        int head = 0;
        int tail = 0;
        int start = map.cell(pose.x, pose.y) * 4 + pose.heading;
        java.util.Arrays.fill(parent, 0, states, -2);
        parent[start] = -1;
        queue[tail++] = start;
        while (head < tail) {
            int s = queue[head++];
            int x0 = s / 4 / n;
            int y0 = s / 4 % n;
            int h0 = s % 4;
            for (int r = 0; r < 3; r++) {
                int h = (h0 + ROTATIONS[r] / 90 + 4) & 3;
                for (int mv : MOVEMENTS) {
                    int d = mv >= 0 ? h : (h + 2) & 3;
                    int x = x0;
                    int y = y0;
                    boolean ok = true;
                    for (int k = 0; k < Math.abs(mv); k++) {
                        if (map.edge(x, y, d) != MazeMap.OPEN
                                || !map.inside(x + MazeMap.dx(d), y + MazeMap.dy(d))) {
                            ok = false;
                            break;
                        }
                        x += MazeMap.dx(d);
                        y += MazeMap.dy(d);
                    }
                    int t = map.cell(x, y) * 4 + h;
                    if (!ok || parent[t] != -2) {
                        continue;
                    }
                    parent[t] = s;
                    act[t * 2] = (byte) r;
                    act[t * 2 + 1] = (byte) mv;
                    if (map.inGoal(x, y)) { // walk back to the first action of the plan
                        while (parent[t] != start) {
                            t = parent[t];
                        }
                        return Answer.move(ROTATIONS[act[t * 2]], act[t * 2 + 1]);
                    }
                    queue[tail++] = t;
                }
            }
        }
        return null;
    }

    // --- debug drawing (the replay viewer's layer; no effect on the moves) -----------

    /**
     * Builds the drawing for this step: text, the walls if they changed, and in run 0 the
     * flood fill as a grid and the way down it from the robot's cell.
     */
    private void draw(String text) {
        int n = map.size();
        debug.clear();
        debug.text(text);
        int walls = 0;
        for (int x = 0; x < n; x++) {
            for (int y = 0; y < n; y++) {
                if (y + 1 < n && map.edge(x, y, MazeMap.UP) == MazeMap.WALL) {
                    walls++;
                }
                if (x + 1 < n && map.edge(x, y, MazeMap.RIGHT) == MazeMap.WALL) {
                    walls++;
                }
            }
        }
        if (walls != wallsDrawn) { // fields are sticky: send the walls when they change
            wallsDrawn = walls;
            debug.empty(Debug.Field.WALLS); // the field, even with no wall yet
            for (int x = 0; x < n; x++) {
                for (int y = 0; y < n; y++) {
                    if (y + 1 < n && map.edge(x, y, MazeMap.UP) == MazeMap.WALL) {
                        debug.wall(x, y, Debug.UP);
                    }
                    if (x + 1 < n && map.edge(x, y, MazeMap.RIGHT) == MazeMap.WALL) {
                        debug.wall(x, y, Debug.RIGHT);
                    }
                }
            }
        }
        if (!flooded) {
            return;
        }
        debug.grid(n, dist, INF);
        int count = 0;
        int x = pose.x;
        int y = pose.y;
        while (count < n * n && dist[map.cell(x, y)] != INF) {
            int here = dist[map.cell(x, y)];
            int next = -1;
            path[2 * count] = x;
            path[2 * count + 1] = y;
            count++;
            for (int dd = 0; dd < 4 && here > 0 && next < 0; dd++) {
                int nx = x + MazeMap.dx(dd);
                int ny = y + MazeMap.dy(dd);
                if (map.edge(x, y, dd) != MazeMap.WALL && map.inside(nx, ny)
                        && dist[map.cell(nx, ny)] == here - 1) {
                    next = dd;
                }
            }
            if (next < 0) {
                break;
            }
            x += MazeMap.dx(next);
            y += MazeMap.dy(next);
        }
        debug.path(path, count);
    }

    // --- the bot interface ---------------------------------------------------------------

    @Override
    public void start(StartInfo info) {
        int n = info.mazeDim();
        if (n >= 2 && n <= MAX_DIM) {
            map = new MazeMap(n);
            dist = new int[n * n];
            queue = new int[n * n * 4];
            parent = new int[n * n * 4];
            act = new byte[n * n * 4 * 2];
            path = new int[n * n * 2];
        } else {
            System.err.println("minimal_bot: cannot map a " + n + "x" + n
                    + " maze; turning on the spot");
        }
        pose.home();
    }

    @Override
    public Answer nextMove(int[] sensors, int run, int step) {
        if (map == null) {
            return Answer.move(90, 0);
        }
        if (run != this.run) { // the reset was accepted: back at the start
            this.run = run;
            pose.home();
        }
        map.sense(pose, sensors);
        flooded = false;
        if (run == 0 && enteredGoal) {
            draw("goal room entered: reset");
            debug.empty(Debug.Field.GRID); // clear the run-0 drawing
            debug.empty(Debug.Field.PATH);
            return Answer.reset().withDebug(debug);
        }
        Answer a = run == 1 ? planMove() : null;
        if (a == null) {
            a = exploreMove();
        }
        draw(run == 1 ? "run 1: shortest known path" : "run 0: flood fill, unknown = open");
        pose.apply(a); // exact: moves only cross edges known to be open
        if (run == 0 && map.inGoal(pose.x, pose.y)) {
            enteredGoal = true;
        }
        return a.withDebug(debug);
    }

    @Override
    public void end(EndInfo info) {
        StringBuilder b = new StringBuilder("minimal_bot: ").append(info.status());
        info.score().ifPresent(s -> b.append(String.format(", score %.3f", s)));
        System.err.println(b);
    }

    /**
     * Plays one match over stdin and stdout.
     *
     * @param args not used
     */
    public static void main(String[] args) {
        System.exit(MazeBot.run(new MinimalBot()));
    }
}
