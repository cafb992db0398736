package mazebot;

import java.util.OptionalDouble;
import java.util.OptionalLong;

/**
 * The end message: {@code {"type":"end","status":"finished","score":22.133,...}}.
 * Fields the server sent as {@code null} (or left out) are empty.
 *
 * @param status {@code finished}, {@code step_limit}, {@code timeout}, {@code crashed},
 *     {@code protocol_error}, ... ({@code ""} if absent)
 * @param score run-1 steps + run-0 steps / 30, when the match finished
 * @param run0Steps the steps of the exploration run, once a reset was accepted
 * @param run1Steps the steps of the timed run, when the match finished
 */
public record EndInfo(String status, OptionalDouble score, OptionalLong run0Steps,
        OptionalLong run1Steps) {
}
