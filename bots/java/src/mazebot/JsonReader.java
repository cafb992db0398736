package mazebot;

/**
 * A tiny JSON reader over one line: enough to read the server's messages (fields in any
 * order, any whitespace, unknown values of any type skipped) and to check a debug object.
 * Errors are {@link IllegalArgumentException}s saying what and where.
 */
final class JsonReader {

    /** Nesting accepted inside skipped values. */
    static final int MAX_DEPTH = 200;

    /** A JSON number: as written, and whether it is written as an integer. */
    static final class Num {
        /** Written without a fraction or an exponent. */
        boolean integer;
        /** Has a leading minus. */
        boolean negative;
        /** The integer's magnitude, unsigned 64-bit, saturated at 2^64 - 1. */
        long magnitude;
        /** The number's value as a double. */
        double value;

        /** @return the value as an int, saturated (a fraction is cut toward zero) */
        int toInt() {
            long v = toLong();
            return v > Integer.MAX_VALUE ? Integer.MAX_VALUE
                    : v < Integer.MIN_VALUE ? Integer.MIN_VALUE : (int) v;
        }

        /** @return the value as a long, saturated (a fraction is cut toward zero) */
        long toLong() {
            if (integer) {
                if (Long.compareUnsigned(magnitude, Long.MAX_VALUE) > 0) {
                    return negative ? Long.MIN_VALUE : Long.MAX_VALUE;
                }
                return negative ? -magnitude : magnitude;
            }
            return Double.isNaN(value) ? 0 : (long) value; // the cast saturates
        }
    }

    private final String s;
    private int p;

    JsonReader(String s) {
        this.s = s;
    }

    /** @return the position of the next character */
    int pos() {
        return p;
    }

    /** @return whether every character was read */
    boolean atEnd() {
        return p >= s.length();
    }

    /** @return the next character, or -1 at the end */
    int peek() {
        return p < s.length() ? s.charAt(p) : -1;
    }

    /** Steps over the next character. */
    void advance() {
        p++;
    }

    IllegalArgumentException error(String why) {
        return new IllegalArgumentException(why + " at character " + p);
    }

    /** Skips spaces, tabs, carriage returns and newlines. */
    void skipWs() {
        while (p < s.length()) {
            char c = s.charAt(p);
            if (c != ' ' && c != '\t' && c != '\n' && c != '\r') {
                break;
            }
            p++;
        }
    }

    /** Reads {@code c} (after whitespace) or fails. */
    void expect(char c) {
        skipWs();
        if (peek() != c) {
            throw error("expected '" + c + "'");
        }
        p++;
    }

    private void word(String w) {
        if (!s.startsWith(w, p)) {
            throw error("unexpected character");
        }
        p += w.length();
    }

    /** @return the string at the reader, decoded */
    String readString() {
        return readString(true);
    }

    private String readString(boolean keep) {
        if (peek() != '"') {
            throw error("expected a string");
        }
        p++;
        StringBuilder out = keep ? new StringBuilder() : null;
        for (;;) {
            if (p >= s.length()) {
                throw error("unterminated string");
            }
            char c = s.charAt(p++);
            if (c == '"') {
                return keep ? out.toString() : null;
            }
            if (c < 0x20) {
                throw error("control character in a string");
            }
            if (c != '\\') {
                if (keep) {
                    out.append(c);
                }
                continue;
            }
            if (p >= s.length()) {
                throw error("unterminated string");
            }
            c = s.charAt(p++);
            char decoded;
            switch (c) {
                case '"', '\\', '/' -> decoded = c;
                case 'b' -> decoded = '\b';
                case 'f' -> decoded = '\f';
                case 'n' -> decoded = '\n';
                case 'r' -> decoded = '\r';
                case 't' -> decoded = '\t';
                case 'u' -> {
                    if (p + 4 > s.length()) {
                        throw error("short \\u escape");
                    }
                    int v = 0;
                    for (int i = 0; i < 4; i++) {
                        int d = Character.digit(s.charAt(p + i), 16);
                        if (d < 0) {
                            throw error("bad \\u escape");
                        }
                        v = v * 16 + d;
                    }
                    p += 4;
                    decoded = (char) v; // surrogate pairs come as two escapes: kept as such
                }
                default -> throw error("bad escape in a string");
            }
            if (keep) {
                out.append(decoded);
            }
        }
    }

    private static boolean isDigit(int c) {
        return c >= '0' && c <= '9';
    }

    /** @return the number at the reader */
    Num readNumber() {
        int start = p;
        Num n = new Num();
        n.integer = true;
        if (peek() == '-') {
            n.negative = true;
            p++;
        }
        if (!isDigit(peek())) {
            throw error("bad number");
        }
        if (peek() == '0') {
            p++;
        } else {
            while (isDigit(peek())) {
                int d = s.charAt(p++) - '0';
                // magnitude * 10 + d, unsigned, saturated
                if (Long.compareUnsigned(n.magnitude, Long.divideUnsigned(-1L - d, 10)) > 0) {
                    n.magnitude = -1L;
                } else {
                    n.magnitude = n.magnitude * 10 + d;
                }
            }
        }
        if (peek() == '.') {
            n.integer = false;
            p++;
            if (!isDigit(peek())) {
                throw error("bad number");
            }
            while (isDigit(peek())) {
                p++;
            }
        }
        if (peek() == 'e' || peek() == 'E') {
            n.integer = false;
            p++;
            if (peek() == '+' || peek() == '-') {
                p++;
            }
            if (!isDigit(peek())) {
                throw error("bad number");
            }
            while (isDigit(peek())) {
                p++;
            }
        }
        n.value = Double.parseDouble(s.substring(start, p));
        return n;
    }

    /**
     * Reads a number, or null.
     *
     * @return the number; {@code null} for a JSON null or a value of another type
     *     (skipped)
     */
    Num readNumberOrNull() {
        int c = peek();
        if (c == '-' || isDigit(c)) {
            return readNumber();
        }
        skipValue(0);
        return null;
    }

    /** Skips one value of any type. */
    void skipValue(int depth) {
        if (depth > MAX_DEPTH) {
            throw error("nested too deeply");
        }
        int c = peek();
        switch (c) {
            case '{' -> skipContainer(depth, '}', true);
            case '[' -> skipContainer(depth, ']', false);
            case '"' -> readString(false);
            case 't' -> word("true");
            case 'f' -> word("false");
            case 'n' -> word("null");
            default -> {
                if (c == '-' || isDigit(c)) {
                    readNumber();
                } else {
                    throw error("expected a value");
                }
            }
        }
    }

    private void skipContainer(int depth, char close, boolean object) {
        p++; // the opening bracket
        skipWs();
        if (peek() == close) {
            p++;
            return;
        }
        for (;;) {
            skipWs();
            if (object) {
                readString(false);
                expect(':');
                skipWs();
            }
            skipValue(depth + 1);
            skipWs();
            if (peek() == ',') {
                p++;
                continue;
            }
            if (peek() == close) {
                p++;
                return;
            }
            throw error(object ? "expected ',' or '}'" : "expected ',' or ']'");
        }
    }

    /**
     * Why {@code json} is not one JSON object (whitespace around it allowed) that is
     * also valid UTF-8 once encoded, or {@code null} if it is.
     */
    static String objectProblem(String json) {
        for (int i = 0; i < json.length(); i++) {
            char c = json.charAt(i);
            if (Character.isHighSurrogate(c) && i + 1 < json.length()
                    && Character.isLowSurrogate(json.charAt(i + 1))) {
                i++;
            } else if (Character.isSurrogate(c)) {
                return "a lone surrogate: not UTF-8";
            }
        }
        JsonReader r = new JsonReader(json);
        try {
            r.skipWs();
            if (r.peek() != '{') {
                return "not a JSON object";
            }
            r.skipValue(0);
            r.skipWs();
            if (!r.atEnd()) {
                return "text after the JSON object";
            }
        } catch (IllegalArgumentException e) {
            return e.getMessage();
        }
        return null;
    }
}
