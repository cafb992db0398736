package mazebot;

/**
 * The wall map of an n x n maze, as the robot's sensors reveal it.
 *
 * <ul>
 * <li>cells are (x, y) with (0, 0) the start corner, x to the right, y up; the cell index
 * is {@code x * n + y} ({@link #cell});
 * <li>directions are absolute: {@link #UP} (+y), {@link #RIGHT} (+x), {@link #DOWN},
 * {@link #LEFT}, clockwise, so {@code (d + 1) & 3} turns right, {@code (d + 3) & 3} left
 * and {@code (d + 2) & 3} is the opposite side; {@link #dx}/{@link #dy} step one cell;
 * <li>every side of every cell is {@link #UNKNOWN}, {@link #OPEN} or {@link #WALL}, kept
 * for both cells that share it; the outer perimeter starts as wall;
 * <li>the goal room is the 2 x 2 block of cells {@code goalLo() .. goalLo() + 1} in x and
 * y ({@code n / 2 - 1 .. n / 2}), tested by {@link #inGoal}.
 * </ul>
 *
 * Strategies (flood fill, A*, route planning) stay in the bots; this class only holds
 * what each of them needs the same way.
 */
public final class MazeMap {

    /** Direction +y. */
    public static final int UP = 0;
    /** Direction +x. */
    public static final int RIGHT = 1;
    /** Direction -y. */
    public static final int DOWN = 2;
    /** Direction -x. */
    public static final int LEFT = 3;

    /** Nothing is known of the edge. */
    public static final int UNKNOWN = 0;
    /** The edge is open. */
    public static final int OPEN = 1;
    /** The edge is a wall. */
    public static final int WALL = 2;

    private static final int[] DX = {0, 1, 0, -1};
    private static final int[] DY = {1, 0, -1, 0};

    private final int n;
    private final byte[] edges;

    /**
     * An all-unknown map with the perimeter set to wall.
     *
     * @param n the side of the maze, at least 1
     */
    public MazeMap(int n) {
        if (n < 1) {
            throw new IllegalArgumentException("maze side " + n);
        }
        this.n = n;
        this.edges = new byte[n * n * 4];
        for (int i = 0; i < n; i++) {
            setEdge(i, 0, DOWN, WALL);
            setEdge(i, n - 1, UP, WALL);
            setEdge(0, i, LEFT, WALL);
            setEdge(n - 1, i, RIGHT, WALL);
        }
    }

    /**
     * @param d a direction
     * @return the x step of direction d: {0, 1, 0, -1}
     */
    public static int dx(int d) {
        return DX[d];
    }

    /**
     * @param d a direction
     * @return the y step of direction d: {1, 0, -1, 0}
     */
    public static int dy(int d) {
        return DY[d];
    }

    /** @return the side of the maze */
    public int size() {
        return n;
    }

    /**
     * @param x a column
     * @param y a row
     * @return whether (x, y) is a cell of the maze
     */
    public boolean inside(int x, int y) {
        return x >= 0 && y >= 0 && x < n && y < n;
    }

    /**
     * @param x a column
     * @param y a row
     * @return the index of cell (x, y): {@code x * n + y}
     */
    public int cell(int x, int y) {
        return x * n + y;
    }

    /**
     * @param x a column
     * @param y a row
     * @param d a direction
     * @return what is known of side d of cell (x, y): UNKNOWN, OPEN or WALL
     */
    public int edge(int x, int y, int d) {
        return edges[cell(x, y) * 4 + d];
    }

    /**
     * Sets side d of cell (x, y), and the same side seen from the neighbour beyond it if
     * that is inside the maze.
     *
     * @param x a column
     * @param y a row
     * @param d a direction
     * @param state UNKNOWN, OPEN or WALL
     */
    public void setEdge(int x, int y, int d, int state) {
        edges[cell(x, y) * 4 + d] = (byte) state;
        int nx = x + DX[d];
        int ny = y + DY[d];
        if (inside(nx, ny)) {
            edges[cell(nx, ny) * 4 + ((d + 2) & 3)] = (byte) state;
        }
    }

    /** @return the smallest x (and y) of the goal room: {@code n / 2 - 1} */
    public int goalLo() {
        return n / 2 - 1;
    }

    /**
     * @param x a column
     * @param y a row
     * @return whether (x, y) is one of the four goal-room cells
     */
    public boolean inGoal(int x, int y) {
        int lo = goalLo();
        return x >= lo && x <= lo + 1 && y >= lo && y <= lo + 1;
    }

    /**
     * Records one sensor reading taken at pose p. Along each ray the first
     * {@code sensors[i]} edges become open (stopping at the maze border), and the next
     * one a wall; a negative reading records nothing.
     *
     * @param p where the robot is
     * @param sensors {left, front, right}
     */
    public void sense(Pose p, int[] sensors) {
        for (int i = 0; i < 3; i++) {
            int d = (p.heading + i + 3) & 3; // left, front, right
            int x = p.x;
            int y = p.y;
            for (int k = 0; k < sensors[i] && inside(x + DX[d], y + DY[d]); k++) {
                setEdge(x, y, d, OPEN);
                x += DX[d];
                y += DY[d];
            }
            if (sensors[i] >= 0) {
                setEdge(x, y, d, WALL);
            }
        }
    }
}
