package mazebot;

/**
 * One answer to a sense message: a move (a rotation, then a movement) or a reset,
 * optionally carrying a debug drawing. Immutable.
 */
public final class Answer {

    private static final Answer RESET = new Answer(0, 0, true, null);

    private final int rotation;
    private final int movement;
    private final boolean reset;
    private final String debugJson;

    private Answer(int rotation, int movement, boolean reset, String debugJson) {
        this.rotation = rotation;
        this.movement = movement;
        this.reset = reset;
        this.debugJson = debugJson;
    }

    /**
     * A move: {@code {"rotation":R,"movement":M}}.
     *
     * @param rotation -90 (turn left), 0 or 90 (turn right), applied before the movement
     * @param movement -3 to 3 cells; negative moves backwards without turning
     * @return the answer
     */
    public static Answer move(int rotation, int movement) {
        return new Answer(rotation, movement, false, null);
    }

    /**
     * A reset, {@code {"reset":true}}: ends the exploration run. Accepted once the robot
     * has ended a move in the goal room during run 0 (otherwise a warning, and the step
     * is used up).
     *
     * @return the answer
     */
    public static Answer reset() {
        return RESET;
    }

    /**
     * This answer with the drawing {@code d} as it is now (a snapshot of
     * {@link Debug#json()}: {@code d} may be changed or cleared afterwards).
     *
     * @param d the drawing; {@code null} or an empty drawing attaches nothing
     * @return a new answer
     */
    public Answer withDebug(Debug d) {
        return new Answer(rotation, movement, reset, d == null ? null : d.json());
    }

    /**
     * This answer with a debug object written by hand. {@link MazeBot#run(Bot)} sends it
     * only if it is one valid JSON object of at most {@link Debug#MAX_BYTES} bytes (and
     * the match's total stays within {@link Debug#MATCH_MAX_BYTES}); otherwise it is left
     * out, with a line on stderr, so a bad debug object never costs the match.
     *
     * @param json the object's text, or {@code null} for none
     * @return a new answer
     */
    public Answer withDebugJson(String json) {
        return new Answer(rotation, movement, reset, json);
    }

    /** @return the rotation of a move (0 for a reset) */
    public int rotation() {
        return rotation;
    }

    /** @return the movement of a move (0 for a reset) */
    public int movement() {
        return movement;
    }

    /** @return whether this is a reset */
    public boolean isReset() {
        return reset;
    }

    /** @return the attached debug object's JSON, or {@code null} */
    public String debugJson() {
        return debugJson;
    }

    /** @return the answer's JSON without its debug object, e.g. {@code {"rotation":0,"movement":1}} */
    @Override
    public String toString() {
        return reset ? "{\"reset\":true}"
                : "{\"rotation\":" + rotation + ",\"movement\":" + movement + "}";
    }
}
