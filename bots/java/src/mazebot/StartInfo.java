package mazebot;

/**
 * The start message: {@code {"type":"start","protocol":1,"maze_dim":12,...}}.
 *
 * @param protocol the protocol version (1)
 * @param mazeDim the side of the maze, e.g. 12
 * @param maxSteps the steps both runs share (1000)
 * @param seed the match's seed, an unsigned 64-bit number kept in a {@code long} with
 *     the same bits ({@link Long#toUnsignedString(long)} prints it); seed your random
 *     generator with it to make a randomized bot reproducible
 * @param moveTimeoutMs the time for each answer after the first, in milliseconds
 */
public record StartInfo(int protocol, int mazeDim, int maxSteps, long seed, int moveTimeoutMs) {
}
