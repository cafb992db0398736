package mazebot;

import java.util.OptionalDouble;
import java.util.OptionalLong;

/**
 * One message from the server, parsed. {@link MazeBot#run(Bot)} uses it; it is public
 * so that a bot's own message handling can be tested.
 */
public final class Message {

    /** The kinds of message. */
    public enum Type {
        /** {@code "type":"start"}: see {@link Message#start()}. */
        START,
        /** {@code "type":"sense"}: see {@link Message#sensors()}, {@link Message#run()}, {@link Message#step()}. */
        SENSE,
        /** {@code "type":"end"}: see {@link Message#end()}. */
        END,
        /** Any other type (or none): to be ignored, room for later protocol versions. */
        OTHER
    }

    private final Type type;
    private final StartInfo start;
    private final int[] sensors;
    private final int run;
    private final int step;
    private final EndInfo end;

    private Message(Type type, StartInfo start, int[] sensors, int run, int step, EndInfo end) {
        this.type = type;
        this.start = start;
        this.sensors = sensors;
        this.run = run;
        this.step = step;
        this.end = end;
    }

    /** @return the kind of message */
    public Type type() {
        return type;
    }

    /** @return the start message's fields ({@code null} unless {@link Type#START}) */
    public StartInfo start() {
        return start;
    }

    /** @return a copy of {left, front, right} ({@code null} unless {@link Type#SENSE}) */
    public int[] sensors() {
        return sensors == null ? null : sensors.clone();
    }

    /** @return the run of a sense message, 0 or 1 */
    public int run() {
        return run;
    }

    /** @return the step of a sense message, from 1 */
    public int step() {
        return step;
    }

    /** @return the end message's fields ({@code null} unless {@link Type#END}) */
    public EndInfo end() {
        return end;
    }

    /**
     * Parses one line (without its {@code \n}; whitespace and a {@code \r} around the
     * object are fine). Fields may come in any order; unknown fields, whatever their
     * type, are skipped; a known field holding a value of another type is taken as
     * absent; numbers are saturated to the Java type.
     *
     * @param line the line
     * @return the message; {@link Type#OTHER} for a type this helper does not know
     * @throws IllegalArgumentException with a short reason when the line is not one JSON
     *     object, or a start lacks {@code maze_dim}, or a sense lacks {@code run} or three
     *     sensors
     */
    public static Message parse(String line) {
        JsonReader r = new JsonReader(line);
        String type = null;
        String status = "";
        int protocol = 1;
        int mazeDim = 0;
        int maxSteps = 1000;
        long seed = 0;
        int moveTimeoutMs = 1000;
        int run = 0;
        int step = 0;
        int[] sensors = new int[3];
        boolean haveDim = false;
        boolean haveRun = false;
        boolean haveSensors = false;
        OptionalDouble score = OptionalDouble.empty();
        OptionalLong run0 = OptionalLong.empty();
        OptionalLong run1 = OptionalLong.empty();

        r.skipWs();
        if (r.peek() != '{') {
            throw r.error("not a JSON object");
        }
        r.advance();
        r.skipWs();
        if (r.peek() == '}') {
            r.advance();
        } else {
            for (;;) {
                r.skipWs();
                String key = r.readString();
                r.expect(':');
                r.skipWs();
                switch (key) {
                    case "type", "status" -> {
                        if (r.peek() == '"') {
                            String v = r.readString();
                            if (key.equals("type")) {
                                type = v;
                            } else {
                                status = v;
                            }
                        } else {
                            r.skipValue(0);
                        }
                    }
                    case "sensors" -> {
                        if (r.peek() != '[') {
                            r.skipValue(0);
                            break;
                        }
                        r.advance();
                        r.skipWs();
                        int count = 0;
                        if (r.peek() == ']') {
                            r.advance();
                        } else {
                            for (;;) {
                                r.skipWs();
                                JsonReader.Num n = r.readNumberOrNull();
                                if (n != null && count < 3) {
                                    sensors[count] = n.toInt();
                                }
                                count++;
                                r.skipWs();
                                if (r.peek() == ',') {
                                    r.advance();
                                    continue;
                                }
                                if (r.peek() == ']') {
                                    r.advance();
                                    break;
                                }
                                throw r.error("expected ',' or ']'");
                            }
                        }
                        haveSensors = count == 3;
                    }
                    case "protocol", "maze_dim", "max_steps", "seed", "move_timeout_ms", "run",
                            "step", "score", "run0_steps", "run1_steps" -> {
                        JsonReader.Num n = r.readNumberOrNull();
                        if (n == null) {
                            break;
                        }
                        switch (key) {
                            case "protocol" -> protocol = n.toInt();
                            case "maze_dim" -> {
                                mazeDim = n.toInt();
                                haveDim = true;
                            }
                            case "max_steps" -> maxSteps = n.toInt();
                            // unsigned 64 bits; a negative seed is taken modulo 2^64
                            case "seed" -> seed = n.integer
                                    ? (n.negative ? -n.magnitude : n.magnitude) : n.toLong();
                            case "move_timeout_ms" -> moveTimeoutMs = n.toInt();
                            case "run" -> {
                                run = n.toInt();
                                haveRun = true;
                            }
                            case "step" -> step = n.toInt();
                            case "score" -> score = OptionalDouble.of(n.value);
                            case "run0_steps" -> run0 = OptionalLong.of(n.toLong());
                            default -> run1 = OptionalLong.of(n.toLong());
                        }
                    }
                    default -> r.skipValue(0);
                }
                r.skipWs();
                if (r.peek() == ',') {
                    r.advance();
                    continue;
                }
                if (r.peek() == '}') {
                    r.advance();
                    break;
                }
                throw r.error("expected ',' or '}'");
            }
        }
        r.skipWs();
        if (!r.atEnd()) {
            throw r.error("text after the JSON object");
        }

        if ("start".equals(type)) {
            if (!haveDim) {
                throw r.error("start message without maze_dim");
            }
            return new Message(Type.START,
                    new StartInfo(protocol, mazeDim, maxSteps, seed, moveTimeoutMs), null, 0, 0,
                    null);
        }
        if ("sense".equals(type)) {
            if (!haveRun || !haveSensors) {
                throw r.error("sense message without run or three sensors");
            }
            return new Message(Type.SENSE, null, sensors, run, step, null);
        }
        if ("end".equals(type)) {
            return new Message(Type.END, null, null, 0, 0, new EndInfo(status, score, run0, run1));
        }
        return new Message(Type.OTHER, null, null, 0, 0, null);
    }
}
