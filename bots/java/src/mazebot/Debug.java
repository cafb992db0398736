package mazebot;

import java.util.ArrayList;
import java.util.Arrays;
import java.util.EnumMap;
import java.util.List;
import java.util.Map;

/**
 * A debug drawing: what the bot believes, drawn by the replay viewer over the maze at
 * this step (docs/PROTOCOL.md, "Debug drawing"). Attach it to an answer with
 * {@link Answer#withDebug(Debug)}:
 *
 * <pre>{@code
 * debug.clear();                              // each step starts empty
 * debug.text("run " + run + ": " + togo + " steps to go");
 * debug.wall(2, 3, Debug.RIGHT);
 * debug.grid(n, dist, INF);                   // dist[x * n + y]; INF is sent as null
 * return Answer.move(0, 1).withDebug(debug);
 * }</pre>
 *
 * <p>(0, 0) is the bottom-left cell, x to the right, y up. Every field is optional and
 * sticky in the viewer (each shows the latest one sent), so send big ones only when they
 * change, and {@link #empty(Field)} to clear one.
 *
 * <p>The builder always yields valid JSON: strings are escaped (a lone surrogate becomes
 * U+FFFD), colours are checked, and an item that would take the object over
 * {@link #MAX_BYTES} bytes is left out (the method returns {@code false} and
 * {@link #dropped()} counts it). {@link MazeBot#run(Bot)} also leaves out a drawing that
 * would take the match's total over {@link #MATCH_MAX_BYTES}.
 */
public final class Debug {

    /** The server keeps at most this many bytes of one step's debug JSON. */
    public static final int MAX_BYTES = 16 * 1024;

    /** ... and this many bytes of debug JSON over a whole match. */
    public static final int MATCH_MAX_BYTES = 64 * 1024;

    /** A text longer than this many characters is cut. */
    public static final int MAX_TEXT_CHARS = 4096;

    /** Wall side: up (+y); the same number as {@link MazeMap#UP}. */
    public static final int UP = 0;
    /** Wall side: right (+x). */
    public static final int RIGHT = 1;
    /** Wall side: down (-y). */
    public static final int DOWN = 2;
    /** Wall side: left (-x). */
    public static final int LEFT = 3;

    private static final String[] SIDES = {"up", "right", "down", "left"};

    /** The fields of a debug object. */
    public enum Field {
        /** {@code "text"}: a line shown with the step. */
        TEXT("text", false),
        /** {@code "walls"}: {@code [[x, y, side], ...]}. */
        WALLS("walls", true),
        /** {@code "cells"}: {@code [[x, y, value], ...]}. */
        CELLS("cells", true),
        /** {@code "grid"}: {@code grid[x][y]}, numbers or null. */
        GRID("grid", false),
        /** {@code "colors"}: {@code [[x, y, "#rrggbb"], ...]}. */
        COLORS("colors", true),
        /** {@code "path"}: {@code [[x, y], ...]}. */
        PATH("path", false);

        private final String key;
        private final boolean list;

        Field(String key, boolean list) {
            this.key = key;
            this.list = list;
        }

        /** @return the field's name in the JSON object */
        public String key() {
            return key;
        }
    }

    private static final Field[] FIELDS = Field.values();

    /** The JSON of each present field's items (a one-value field: exactly one). */
    private final Map<Field, List<String>> items = new EnumMap<>(Field.class);
    /** The UTF-8 bytes of each field's items together. */
    private final int[] bytes = new int[FIELDS.length];
    private int dropped;

    /** An empty drawing. */
    public Debug() {
    }

    /** Empties the drawing: call it at the start of every step. */
    public void clear() {
        items.clear();
        Arrays.fill(bytes, 0);
        dropped = 0;
    }

    /** @return how many items were left out since {@link #clear()} (too big, or invalid) */
    public int dropped() {
        return dropped;
    }

    /**
     * A line of text shown with the step (replaces an earlier one; cut at
     * {@link #MAX_TEXT_CHARS} characters).
     *
     * @param text the text; {@code null} is sent as {@code ""}
     * @return whether it was added
     */
    public boolean text(String text) {
        String t = text == null ? "" : text;
        if (t.length() > MAX_TEXT_CHARS) {
            int cut = MAX_TEXT_CHARS;
            if (Character.isHighSurrogate(t.charAt(cut - 1))) {
                cut--;
            }
            t = t.substring(0, cut);
        }
        StringBuilder b = new StringBuilder(t.length() + 2);
        appendString(b, t);
        return add(Field.TEXT, b.toString());
    }

    /**
     * A wall the bot believes in.
     *
     * @param x the cell's column
     * @param y the cell's row
     * @param side {@link #UP}, {@link #RIGHT}, {@link #DOWN} or {@link #LEFT}
     * @return whether it was added
     */
    public boolean wall(int x, int y, int side) {
        if (side < 0 || side > 3) {
            dropped++;
            return false;
        }
        return add(Field.WALLS, "[" + x + "," + y + ",\"" + SIDES[side] + "\"]");
    }

    /**
     * A number written in a cell.
     *
     * @param x the cell's column
     * @param y the cell's row
     * @param value the number
     * @return whether it was added
     */
    public boolean cellInt(int x, int y, long value) {
        return add(Field.CELLS, "[" + x + "," + y + "," + value + "]");
    }

    /**
     * A short text written in a cell.
     *
     * @param x the cell's column
     * @param y the cell's row
     * @param text the text ({@code null}: {@code ""})
     * @return whether it was added
     */
    public boolean cellText(int x, int y, String text) {
        StringBuilder b = new StringBuilder();
        b.append('[').append(x).append(',').append(y).append(',');
        appendString(b, text == null ? "" : text);
        return add(Field.CELLS, b.append(']').toString());
    }

    /**
     * Values for the whole n x n maze (replaces an earlier grid).
     *
     * @param n the side of the maze
     * @param values {@code values[x * n + y]}, the maze file's order (at least n * n)
     * @param nullValue a value sent as {@code null} (nothing shown in that cell)
     * @return whether it was added
     */
    public boolean grid(int n, int[] values, int nullValue) {
        if (n < 0 || (n > 0 && (values == null || values.length < (long) n * n))) {
            dropped++;
            return false;
        }
        StringBuilder b = new StringBuilder(4 * n * n + 2);
        b.append('[');
        for (int x = 0; x < n && b.length() <= MAX_BYTES; x++) {
            b.append(x == 0 ? "[" : ",[");
            for (int y = 0; y < n; y++) {
                int v = values[x * n + y];
                if (y > 0) {
                    b.append(',');
                }
                if (v == nullValue) {
                    b.append("null");
                } else {
                    b.append(v);
                }
            }
            b.append(']');
        }
        return add(Field.GRID, b.append(']').toString());
    }

    /**
     * Values for the whole maze as columns, {@code columns[x][y]} (replaces an earlier
     * grid).
     *
     * @param columns one array per column x, indexed by y
     * @param nullValue a value sent as {@code null}
     * @return whether it was added
     */
    public boolean grid(int[][] columns, int nullValue) {
        if (columns == null) {
            dropped++;
            return false;
        }
        StringBuilder b = new StringBuilder();
        b.append('[');
        for (int x = 0; x < columns.length && b.length() <= MAX_BYTES; x++) {
            b.append(x == 0 ? "[" : ",[");
            int[] col = columns[x] == null ? new int[0] : columns[x];
            for (int y = 0; y < col.length; y++) {
                if (y > 0) {
                    b.append(',');
                }
                if (col[y] == nullValue) {
                    b.append("null");
                } else {
                    b.append(col[y]);
                }
            }
            b.append(']');
        }
        return add(Field.GRID, b.append(']').toString());
    }

    /**
     * A cell colour.
     *
     * @param x the cell's column
     * @param y the cell's row
     * @param hex {@code "#rgb"} or {@code "#rrggbb"}; anything else is refused
     * @return whether it was added
     */
    public boolean color(int x, int y, String hex) {
        if (!isColor(hex)) {
            dropped++;
            return false;
        }
        return add(Field.COLORS, "[" + x + "," + y + ",\"" + hex + "\"]");
    }

    /**
     * @param hex a text
     * @return whether it is a colour the viewer accepts, {@code #rgb} or {@code #rrggbb}
     */
    public static boolean isColor(String hex) {
        if (hex == null || (hex.length() != 4 && hex.length() != 7) || hex.charAt(0) != '#') {
            return false;
        }
        for (int i = 1; i < hex.length(); i++) {
            char c = hex.charAt(i);
            if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F'))) {
                return false;
            }
        }
        return true;
    }

    /**
     * A planned path (replaces an earlier one; no cell sends an empty path, which clears
     * the drawn one).
     *
     * @param xy {@code {x0, y0, x1, y1, ...}}
     * @param count how many cells of {@code xy} to send
     * @return whether it was added
     */
    public boolean path(int[] xy, int count) {
        if (count < 0 || (count > 0 && (xy == null || xy.length < 2L * count))) {
            dropped++;
            return false;
        }
        StringBuilder b = new StringBuilder(8 * count + 2);
        b.append('[');
        for (int i = 0; i < count && b.length() <= MAX_BYTES; i++) {
            if (i > 0) {
                b.append(',');
            }
            b.append('[').append(xy[2 * i]).append(',').append(xy[2 * i + 1]).append(']');
        }
        return add(Field.PATH, b.append(']').toString());
    }

    /**
     * A planned path through every cell of {@code xy}.
     *
     * @param xy {@code {x0, y0, x1, y1, ...}}
     * @return whether it was added
     */
    public boolean path(int[] xy) {
        return path(xy, xy == null ? 0 : xy.length / 2);
    }

    /**
     * Sends a field empty ({@code "text":""} or an empty list), which clears what the
     * viewer shows for it; any items of it added so far are removed.
     *
     * @param field the field
     * @return whether it was set
     */
    public boolean empty(Field field) {
        if (field == null) {
            dropped++;
            return false;
        }
        if (!field.list) {
            return add(field, field == Field.TEXT ? "\"\"" : "[]");
        }
        int f = field.ordinal();
        List<String> old = items.put(field, new ArrayList<>());
        int oldBytes = bytes[f];
        bytes[f] = 0;
        if (size() > MAX_BYTES) {
            restore(field, old);
            bytes[f] = oldBytes;
            dropped++;
            return false;
        }
        return true;
    }

    /** @return the size of {@link #json()} in UTF-8 bytes (2 when no field is set) */
    public int size() {
        int n = 2;
        int fields = 0;
        for (Field field : FIELDS) {
            List<String> list = items.get(field);
            if (list == null) {
                continue;
            }
            fields++;
            n += field.key.length() + 3 + bytes[field.ordinal()]; // "key":
            if (field.list) {
                n += 2 + Math.max(list.size() - 1, 0); // [ , ]
            }
        }
        return n + Math.max(fields - 1, 0);
    }

    /** @return the object's compact JSON, or {@code null} when no field is set */
    public String json() {
        StringBuilder b = new StringBuilder(size());
        for (Field field : FIELDS) {
            List<String> list = items.get(field);
            if (list == null) {
                continue;
            }
            b.append(b.length() == 0 ? "{\"" : ",\"").append(field.key).append("\":");
            if (field.list) {
                b.append('[').append(String.join(",", list)).append(']');
            } else {
                b.append(list.get(0));
            }
        }
        return b.length() == 0 ? null : b.append('}').toString();
    }

    /** @return {@link #json()}, or {@code "{}"} when no field is set */
    @Override
    public String toString() {
        String j = json();
        return j == null ? "{}" : j;
    }

    /** Keeps {@code item} in {@code field} if the object stays within MAX_BYTES. */
    private boolean add(Field field, String item) {
        int f = field.ordinal();
        int itemBytes = utf8Length(item);
        int oldBytes = bytes[f];
        List<String> old;
        if (field.list) {
            old = items.get(field);
            items.computeIfAbsent(field, k -> new ArrayList<>()).add(item);
            bytes[f] += itemBytes;
        } else {
            old = items.put(field, List.of(item));
            bytes[f] = itemBytes;
        }
        if (itemBytes > MAX_BYTES || size() > MAX_BYTES) {
            if (field.list && old != null) {
                old.remove(old.size() - 1);
            } else {
                restore(field, old);
            }
            bytes[f] = oldBytes;
            dropped++;
            return false;
        }
        return true;
    }

    /** Puts back a field's earlier items ({@code null}: the field was absent). */
    private void restore(Field field, List<String> old) {
        if (old == null) {
            items.remove(field);
        } else {
            items.put(field, old);
        }
    }

    /** The UTF-8 length of s (which holds no lone surrogate: appendString replaces them). */
    static int utf8Length(String s) {
        int n = 0;
        for (int i = 0; i < s.length(); i++) {
            char c = s.charAt(i);
            if (c < 0x80) {
                n++;
            } else if (c < 0x800) {
                n += 2;
            } else if (Character.isHighSurrogate(c) && i + 1 < s.length()
                    && Character.isLowSurrogate(s.charAt(i + 1))) {
                n += 4;
                i++;
            } else {
                n += 3;
            }
        }
        return n;
    }

    /**
     * Appends {@code s} as a JSON string: quotes, backslashes and control characters
     * escaped, lone surrogates (not UTF-8) replaced by U+FFFD.
     */
    static void appendString(StringBuilder b, String s) {
        b.append('"');
        for (int i = 0; i < s.length(); i++) {
            char c = s.charAt(i);
            switch (c) {
                case '"' -> b.append("\\\"");
                case '\\' -> b.append("\\\\");
                case '\n' -> b.append("\\n");
                case '\r' -> b.append("\\r");
                case '\t' -> b.append("\\t");
                default -> {
                    if (c < 0x20 || c == 0x7f) {
                        b.append(String.format("\\u%04x", (int) c));
                    } else if (Character.isHighSurrogate(c) && i + 1 < s.length()
                            && Character.isLowSurrogate(s.charAt(i + 1))) {
                        b.append(c).append(s.charAt(++i));
                    } else if (Character.isSurrogate(c)) {
                        b.append('\ufffd');
                    } else {
                        b.append(c);
                    }
                }
            }
        }
        b.append('"');
    }
}
