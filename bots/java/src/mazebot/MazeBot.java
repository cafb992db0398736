package mazebot;

import java.io.BufferedOutputStream;
import java.io.ByteArrayInputStream;
import java.io.ByteArrayOutputStream;
import java.io.FileDescriptor;
import java.io.FileInputStream;
import java.io.FileOutputStream;
import java.io.IOException;
import java.io.InputStream;
import java.io.OutputStream;
import java.io.PrintStream;
import java.nio.charset.StandardCharsets;

/**
 * Protocol v1 (docs/PROTOCOL.md): plays one match over stdin and stdout for a
 * {@link Bot}.
 *
 * <pre>{@code
 * public static void main(String[] args) {
 *     System.exit(MazeBot.run(new MyBot()));
 * }
 * }</pre>
 *
 * <p>{@link #run(Bot)} reads the server's lines (up to 64 KiB; a longer one is logged and
 * skipped), parses them with {@link Message#parse(String)}, calls the bot, and writes one
 * line per answer, flushed at once. While it runs, {@code System.out} is
 * {@code System.err} (the bot's log, which the server keeps and never reads) and
 * {@code System.in} is empty, so a stray {@code println} can never be taken as an answer
 * and nothing can eat the server's messages; the protocol goes through private streams
 * on the real file descriptors 0 and 1.
 */
public final class MazeBot {

    /** The longest input line read, not counting its {@code \n} (the protocol's 64 KiB). */
    public static final int MAX_LINE = 65536;

    private MazeBot() {
    }

    /**
     * Plays one match.
     *
     * @param bot the bot
     * @return 0 after the end message, or when stdin closes or the server stops reading;
     *     1 after a line that cannot be read as a message (a line on stderr says why), so
     *     {@code System.exit(MazeBot.run(bot))} exits with the right status. An exception
     *     thrown by the bot is passed on.
     */
    public static int run(Bot bot) {
        if (bot == null) {
            throw new IllegalArgumentException("MazeBot.run needs a bot");
        }
        PrintStream userOut = System.out;
        InputStream userIn = System.in;
        userOut.flush();
        InputStream in = new FileInputStream(FileDescriptor.in);
        OutputStream out = new BufferedOutputStream(new FileOutputStream(FileDescriptor.out), 1 << 17);
        System.setOut(System.err);
        System.setIn(new ByteArrayInputStream(new byte[0]));
        try {
            return loop(bot, in, out);
        } finally {
            System.err.flush();
            System.setOut(userOut);
            System.setIn(userIn);
        }
    }

    private static int loop(Bot bot, InputStream in, OutputStream out) {
        LineReader lines = new LineReader(in);
        long debugSent = 0;
        boolean warnedBad = false;
        boolean warnedStep = false;
        boolean warnedMatch = false;
        for (;;) {
            String line;
            try {
                line = lines.next();
            } catch (IOException e) {
                log("cannot read stdin (" + e.getMessage() + ")");
                return 0;
            }
            if (line == null) {
                return 0; // the server closed our stdin
            }
            if (lines.tooLong) {
                log("ignored a line longer than 64 KiB: " + head(line));
                continue;
            }
            line = stripEnd(line);
            if (line.isEmpty()) {
                continue;
            }
            Message msg;
            try {
                msg = Message.parse(line);
            } catch (IllegalArgumentException e) {
                log("cannot read a message (" + e.getMessage() + "): " + head(line));
                return 1;
            }
            switch (msg.type()) {
                case START -> bot.start(msg.start());
                case SENSE -> {
                    Answer a = bot.nextMove(msg.sensors(), msg.run(), msg.step());
                    if (a == null) {
                        log("step " + msg.step() + ": nextMove returned null; sent a turn on the spot");
                        a = Answer.move(90, 0);
                    }
                    String debug = a.debugJson();
                    if (debug != null) {
                        int size = Debug.utf8Length(debug);
                        String problem = JsonReader.objectProblem(debug);
                        if (size > Debug.MAX_BYTES) {
                            if (!warnedStep) {
                                log("step " + msg.step() + ": debug object of " + size
                                        + " bytes, over " + Debug.MAX_BYTES + ": not sent");
                                warnedStep = true;
                            }
                            debug = null;
                        } else if (problem != null) {
                            if (!warnedBad) {
                                log("step " + msg.step() + ": debug object not sent (" + problem + ")");
                                warnedBad = true;
                            }
                            debug = null;
                        } else if (debugSent + size > Debug.MATCH_MAX_BYTES) {
                            if (!warnedMatch) {
                                log("step " + msg.step() + ": the match's debug objects would go over "
                                        + Debug.MATCH_MAX_BYTES + " bytes: those that do are not sent");
                                warnedMatch = true;
                            }
                            debug = null;
                        } else {
                            debugSent += size;
                        }
                    }
                    StringBuilder b = new StringBuilder(64 + (debug == null ? 0 : debug.length()));
                    String plain = a.toString();
                    b.append(plain, 0, plain.length() - 1); // without its closing brace
                    if (debug != null) {
                        b.append(",\"debug\":").append(debug.strip());
                    }
                    b.append("}\n");
                    try {
                        out.write(b.toString().getBytes(StandardCharsets.UTF_8));
                        out.flush();
                    } catch (IOException e) {
                        return 0; // the server stopped listening: nothing left to do
                    }
                }
                case END -> {
                    bot.end(msg.end());
                    return 0;
                }
                default -> {
                    // other message types: ignored (room for later protocol versions)
                }
            }
        }
    }

    /** The line without trailing {@code \r}, spaces and tabs. */
    private static String stripEnd(String line) {
        int end = line.length();
        while (end > 0) {
            char c = line.charAt(end - 1);
            if (c != '\r' && c != ' ' && c != '\t') {
                break;
            }
            end--;
        }
        return line.substring(0, end);
    }

    private static String head(String line) {
        return line.length() > 200 ? line.substring(0, 200) + "..." : line;
    }

    private static void log(String what) {
        System.err.println("mazebot: " + what);
        System.err.flush();
    }

    /** Reads lines of UTF-8 bytes, keeping at most MAX_LINE bytes of each. */
    private static final class LineReader {
        private final InputStream in;
        private final byte[] buf = new byte[1 << 16];
        private int pos;
        private int len;
        private final ByteArrayOutputStream line = new ByteArrayOutputStream(256);
        /** The last line returned was longer than MAX_LINE (it holds its beginning). */
        boolean tooLong;

        LineReader(InputStream in) {
            this.in = in;
        }

        /** @return the next line without its {@code \n}, or null at the end of the input */
        String next() throws IOException {
            line.reset();
            tooLong = false;
            boolean any = false;
            for (;;) {
                if (pos == len) {
                    len = in.read(buf);
                    pos = 0;
                    if (len <= 0) {
                        len = 0;
                        return any ? decode() : null;
                    }
                }
                any = true;
                int start = pos;
                while (pos < len && buf[pos] != '\n') {
                    pos++;
                }
                int keep = Math.min(pos - start, MAX_LINE - line.size());
                line.write(buf, start, keep);
                if (keep < pos - start) {
                    tooLong = true;
                }
                if (pos < len) {
                    pos++; // the newline
                    return decode();
                }
            }
        }

        private String decode() {
            return line.toString(StandardCharsets.UTF_8);
        }
    }
}
