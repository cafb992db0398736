package mazebot;

/** Where the robot is: its cell and the absolute direction it faces (dead reckoning). */
public final class Pose {

    /** The column, 0 at the left. */
    public int x;
    /** The row, 0 at the bottom. */
    public int y;
    /** {@link MazeMap#UP}, {@link MazeMap#RIGHT}, {@link MazeMap#DOWN} or {@link MazeMap#LEFT}. */
    public int heading;

    /** The start of every run: (0, 0), facing up. */
    public Pose() {
        home();
    }

    /** Puts the robot back at the start: (0, 0), facing up. */
    public void home() {
        x = 0;
        y = 0;
        heading = MazeMap.UP;
    }

    /**
     * Moves the pose by answer a (rotation first, then movement cells, negative =
     * backward), as the referee does: a rotation other than -90 or 90 turns nothing, a
     * movement beyond 3 cells is cut to 3; a reset leaves the pose unchanged. Exact as long as the bot only moves across
     * edges it knows to be open (a wall would stop the real robot short).
     *
     * @param a the answer sent
     */
    public void apply(Answer a) {
        if (a.isReset()) {
            return;
        }
        if (a.rotation() == 90) {
            heading = (heading + 1) & 3;
        } else if (a.rotation() == -90) {
            heading = (heading + 3) & 3;
        }
        int d = a.movement() >= 0 ? heading : (heading + 2) & 3;
        int cells = Math.min(Math.abs(a.movement()), 3);
        x += MazeMap.dx(d) * cells;
        y += MazeMap.dy(d) * cells;
    }

    /** @return e.g. {@code (3, 4) facing 1} */
    @Override
    public String toString() {
        return "(" + x + ", " + y + ") facing " + heading;
    }
}
