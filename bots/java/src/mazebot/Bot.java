package mazebot;

/**
 * A bot: what {@link MazeBot#run(Bot)} calls for each message of the server.
 *
 * <p>Only {@link #nextMove} is required, so a bot can be a lambda:
 *
 * <pre>{@code
 * System.exit(MazeBot.run((sensors, run, step) ->
 *         sensors[1] > 0 ? Answer.move(0, 1) : Answer.move(90, 0)));
 * }</pre>
 */
@FunctionalInterface
public interface Bot {

    /**
     * Called once, with the start message, before the first move.
     *
     * @param info the side of the maze, the seed (for a reproducible random bot), the
     *     step budget and the time per answer
     */
    default void start(StartInfo info) {
    }

    /**
     * Called once per step; its answer is sent to the server at once.
     *
     * @param sensors {left, front, right}: how many open cells there are between the
     *     robot and the nearest wall in each direction, relative to its heading
     * @param run 0 (exploration) or 1 (the timed run)
     * @param step the shared step counter, 1 to 1000 across both runs
     * @return {@link Answer#move(int, int)} or {@link Answer#reset()}, optionally with a
     *     debug drawing attached ({@link Answer#withDebug(Debug)})
     */
    Answer nextMove(int[] sensors, int run, int step);

    /**
     * Called once, with the end message; the match is over and stdin is closed next.
     *
     * @param info how the match ended, and its score if it finished
     */
    default void end(EndInfo info) {
    }
}
