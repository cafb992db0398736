/*
 * mazebot.c: protocol v1 for C bots (see mazebot.h and docs/PROTOCOL.md).
 *
 * Reads the server's messages line by line, parses them with a small JSON
 * reader (any field order, any whitespace, unknown fields of any type
 * skipped), calls the bot's callbacks and writes one flushed JSON line per
 * answer. Only libc and POSIX (dup, dup2, open) are used.
 */
#define _POSIX_C_SOURCE 200809L

#include "mazebot.h"

#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ------------------------------------------------------------------------ */
/* A tiny JSON reader over one line.                                         */

#define MAX_DEPTH 200 /* nesting accepted inside skipped values */

typedef struct reader {
    const char *p;
    const char *end;
    const char *why; /* first error */
} reader;

static int fail(reader *r, const char *why)
{
    if (r->why == NULL)
        r->why = why;
    return -1;
}

static void skip_ws(reader *r)
{
    while (r->p < r->end && (*r->p == ' ' || *r->p == '\t' || *r->p == '\n' || *r->p == '\r'))
        r->p++;
}

static int peek(const reader *r)
{
    return r->p < r->end ? (unsigned char)*r->p : -1;
}

static int expect_word(reader *r, const char *word)
{
    size_t n = strlen(word);
    if ((size_t)(r->end - r->p) < n || memcmp(r->p, word, n) != 0)
        return fail(r, "unexpected character");
    r->p += n;
    return 0;
}

static int hex4(reader *r, unsigned *out)
{
    unsigned v = 0;
    if (r->end - r->p < 4)
        return fail(r, "short \\u escape");
    for (int i = 0; i < 4; i++) {
        int c = (unsigned char)r->p[i];
        v <<= 4;
        if (c >= '0' && c <= '9')
            v |= (unsigned)(c - '0');
        else if (c >= 'a' && c <= 'f')
            v |= (unsigned)(c - 'a' + 10);
        else if (c >= 'A' && c <= 'F')
            v |= (unsigned)(c - 'A' + 10);
        else
            return fail(r, "bad \\u escape");
    }
    r->p += 4;
    *out = v;
    return 0;
}

/* Appends a byte to out (cap bytes including the final NUL); drops it if full. */
static void put(char *out, size_t cap, size_t *len, char c)
{
    if (out != NULL && *len + 1 < cap)
        out[*len] = c;
    (*len)++;
}

static void put_utf8(char *out, size_t cap, size_t *len, unsigned cp)
{
    if (cp < 0x80) {
        put(out, cap, len, (char)cp);
    } else if (cp < 0x800) {
        put(out, cap, len, (char)(0xC0 | (cp >> 6)));
        put(out, cap, len, (char)(0x80 | (cp & 0x3F)));
    } else if (cp < 0x10000) {
        put(out, cap, len, (char)(0xE0 | (cp >> 12)));
        put(out, cap, len, (char)(0x80 | ((cp >> 6) & 0x3F)));
        put(out, cap, len, (char)(0x80 | (cp & 0x3F)));
    } else {
        put(out, cap, len, (char)(0xF0 | (cp >> 18)));
        put(out, cap, len, (char)(0x80 | ((cp >> 12) & 0x3F)));
        put(out, cap, len, (char)(0x80 | ((cp >> 6) & 0x3F)));
        put(out, cap, len, (char)(0x80 | (cp & 0x3F)));
    }
}

/* Reads a string; its decoded text (cut to cap-1 bytes) goes to out if not NULL. */
static int read_string(reader *r, char *out, size_t cap)
{
    size_t len = 0;
    if (peek(r) != '"')
        return fail(r, "expected a string");
    r->p++;
    for (;;) {
        if (r->p >= r->end)
            return fail(r, "unterminated string");
        unsigned char c = (unsigned char)*r->p++;
        if (c == '"')
            break;
        if (c < 0x20)
            return fail(r, "control character in a string");
        if (c != '\\') {
            put(out, cap, &len, (char)c);
            continue;
        }
        if (r->p >= r->end)
            return fail(r, "unterminated string");
        c = (unsigned char)*r->p++;
        switch (c) {
        case '"': put(out, cap, &len, '"'); break;
        case '\\': put(out, cap, &len, '\\'); break;
        case '/': put(out, cap, &len, '/'); break;
        case 'b': put(out, cap, &len, '\b'); break;
        case 'f': put(out, cap, &len, '\f'); break;
        case 'n': put(out, cap, &len, '\n'); break;
        case 'r': put(out, cap, &len, '\r'); break;
        case 't': put(out, cap, &len, '\t'); break;
        case 'u': {
            unsigned cp;
            if (hex4(r, &cp) != 0)
                return -1;
            if (cp >= 0xD800 && cp < 0xDC00 && r->end - r->p >= 6 && r->p[0] == '\\' &&
                r->p[1] == 'u') {
                const char *save = r->p;
                unsigned lo;
                r->p += 2;
                if (hex4(r, &lo) == 0 && lo >= 0xDC00 && lo < 0xE000) {
                    cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
                } else {
                    r->p = save;
                    r->why = NULL;
                    cp = 0xFFFD;
                }
            } else if (cp >= 0xD800 && cp < 0xE000) {
                cp = 0xFFFD; /* a lone surrogate */
            }
            put_utf8(out, cap, &len, cp);
            break;
        }
        default:
            return fail(r, "bad escape in a string");
        }
    }
    if (out != NULL && cap > 0)
        out[len < cap ? len : cap - 1] = '\0';
    return 0;
}

/* A JSON number: its value as a double and, when it is written as an integer,
 * as a sign and a magnitude saturated at ULLONG_MAX. */
typedef struct number {
    double value;
    int is_integer;
    int negative;
    unsigned long long magnitude;
} number;

static int is_digit(int c)
{
    return c >= '0' && c <= '9';
}

static int read_number(reader *r, number *out)
{
    const char *start = r->p;
    out->is_integer = 1;
    out->negative = 0;
    out->magnitude = 0;
    if (peek(r) == '-') {
        out->negative = 1;
        r->p++;
    }
    if (!is_digit(peek(r)))
        return fail(r, "bad number");
    if (peek(r) == '0') {
        r->p++;
    } else {
        while (is_digit(peek(r))) {
            unsigned d = (unsigned)(*r->p++ - '0');
            if (out->magnitude > (ULLONG_MAX - d) / 10)
                out->magnitude = ULLONG_MAX;
            else
                out->magnitude = out->magnitude * 10 + d;
        }
    }
    if (peek(r) == '.') {
        out->is_integer = 0;
        r->p++;
        if (!is_digit(peek(r)))
            return fail(r, "bad number");
        while (is_digit(peek(r)))
            r->p++;
    }
    if (peek(r) == 'e' || peek(r) == 'E') {
        out->is_integer = 0;
        r->p++;
        if (peek(r) == '+' || peek(r) == '-')
            r->p++;
        if (!is_digit(peek(r)))
            return fail(r, "bad number");
        while (is_digit(peek(r)))
            r->p++;
    }
    char buf[512];
    size_t n = (size_t)(r->p - start);
    if (n < sizeof buf) {
        memcpy(buf, start, n);
        buf[n] = '\0';
        out->value = strtod(buf, NULL);
    } else {
        out->value = out->negative ? -1e308 : 1e308; /* absurdly long: "huge" */
    }
    return 0;
}

static int skip_value(reader *r, int depth);

static int skip_container(reader *r, int depth, char close, int object)
{
    r->p++; /* the opening bracket */
    skip_ws(r);
    if (peek(r) == close) {
        r->p++;
        return 0;
    }
    for (;;) {
        skip_ws(r);
        if (object) {
            if (read_string(r, NULL, 0) != 0)
                return -1;
            skip_ws(r);
            if (peek(r) != ':')
                return fail(r, "expected ':'");
            r->p++;
            skip_ws(r);
        }
        if (skip_value(r, depth + 1) != 0)
            return -1;
        skip_ws(r);
        if (peek(r) == ',') {
            r->p++;
            continue;
        }
        if (peek(r) == close) {
            r->p++;
            return 0;
        }
        return fail(r, object ? "expected ',' or '}'" : "expected ',' or ']'");
    }
}

static int skip_value(reader *r, int depth)
{
    number num;
    if (depth > MAX_DEPTH)
        return fail(r, "nested too deeply");
    switch (peek(r)) {
    case '{': return skip_container(r, depth, '}', 1);
    case '[': return skip_container(r, depth, ']', 0);
    case '"': return read_string(r, NULL, 0);
    case 't': return expect_word(r, "true");
    case 'f': return expect_word(r, "false");
    case 'n': return expect_word(r, "null");
    default:
        if (peek(r) == '-' || is_digit(peek(r)))
            return read_number(r, &num);
        return fail(r, "expected a value");
    }
}

/* Clamps a number to an int (rounding toward zero). */
static int to_int(const number *n)
{
    if (n->is_integer) {
        if (n->negative)
            return n->magnitude > (unsigned long long)INT_MAX ? INT_MIN
                                                              : -(int)n->magnitude;
        return n->magnitude > (unsigned long long)INT_MAX ? INT_MAX : (int)n->magnitude;
    }
    if (!(n->value == n->value))
        return 0;
    if (n->value >= (double)INT_MAX)
        return INT_MAX;
    if (n->value <= (double)INT_MIN)
        return INT_MIN;
    return (int)n->value;
}

static long to_long(const number *n)
{
    if (n->is_integer) {
        if (n->negative)
            return n->magnitude > (unsigned long long)LONG_MAX ? LONG_MIN
                                                               : -(long)n->magnitude;
        return n->magnitude > (unsigned long long)LONG_MAX ? LONG_MAX : (long)n->magnitude;
    }
    if (!(n->value == n->value))
        return 0;
    if (n->value >= (double)LONG_MAX)
        return LONG_MAX;
    if (n->value <= (double)LONG_MIN)
        return LONG_MIN;
    return (long)n->value;
}

/* Reads a number, or null (then *is_null = 1). Any other value: skipped, error. */
static int read_number_or_null(reader *r, number *n, int *is_null)
{
    *is_null = 0;
    if (peek(r) == 'n') {
        *is_null = 1;
        return expect_word(r, "null");
    }
    if (peek(r) == '-' || is_digit(peek(r)))
        return read_number(r, n);
    if (skip_value(r, 0) != 0)
        return -1;
    return 1; /* some other type: treated as absent */
}

int mb_parse_message(const char *line, unsigned long len, mb_message *msg, char *err,
                     unsigned long errlen)
{
    reader r = {line, line + len, NULL};
    char type[32] = "";
    int have_type = 0, have_dim = 0, have_run = 0, have_sensors = 0;

    memset(msg, 0, sizeof *msg);
    msg->start.protocol = 1;
    msg->start.max_steps = 1000;
    msg->start.move_timeout_ms = 1000;
    if (err != NULL && errlen > 0)
        err[0] = '\0';

    skip_ws(&r);
    if (peek(&r) != '{') {
        fail(&r, "not a JSON object");
        goto bad;
    }
    r.p++;
    skip_ws(&r);
    if (peek(&r) == '}') {
        r.p++;
    } else {
        for (;;) {
            char key[32];
            number num;
            int is_null, rc;
            skip_ws(&r);
            if (read_string(&r, key, sizeof key) != 0)
                goto bad;
            skip_ws(&r);
            if (peek(&r) != ':') {
                fail(&r, "expected ':'");
                goto bad;
            }
            r.p++;
            skip_ws(&r);
            if (strcmp(key, "type") == 0 && peek(&r) == '"') {
                if (read_string(&r, type, sizeof type) != 0)
                    goto bad;
                have_type = 1;
            } else if (strcmp(key, "status") == 0 && peek(&r) == '"') {
                if (read_string(&r, msg->end.status, sizeof msg->end.status) != 0)
                    goto bad;
            } else if (strcmp(key, "sensors") == 0 && peek(&r) == '[') {
                int count = 0;
                r.p++;
                skip_ws(&r);
                if (peek(&r) == ']') {
                    r.p++;
                } else {
                    for (;;) {
                        skip_ws(&r);
                        rc = read_number_or_null(&r, &num, &is_null);
                        if (rc < 0)
                            goto bad;
                        if (rc == 0 && !is_null && count < 3)
                            msg->sensors[count] = to_int(&num);
                        count++;
                        skip_ws(&r);
                        if (peek(&r) == ',') {
                            r.p++;
                            continue;
                        }
                        if (peek(&r) == ']') {
                            r.p++;
                            break;
                        }
                        fail(&r, "expected ',' or ']'");
                        goto bad;
                    }
                }
                have_sensors = count == 3;
            } else if (strcmp(key, "protocol") == 0 || strcmp(key, "maze_dim") == 0 ||
                       strcmp(key, "max_steps") == 0 || strcmp(key, "seed") == 0 ||
                       strcmp(key, "move_timeout_ms") == 0 || strcmp(key, "run") == 0 ||
                       strcmp(key, "step") == 0 || strcmp(key, "score") == 0 ||
                       strcmp(key, "run0_steps") == 0 || strcmp(key, "run1_steps") == 0) {
                rc = read_number_or_null(&r, &num, &is_null);
                if (rc < 0)
                    goto bad;
                if (rc == 0 && !is_null) {
                    if (strcmp(key, "protocol") == 0) {
                        msg->start.protocol = to_int(&num);
                    } else if (strcmp(key, "maze_dim") == 0) {
                        msg->start.maze_dim = to_int(&num);
                        have_dim = 1;
                    } else if (strcmp(key, "max_steps") == 0) {
                        msg->start.max_steps = to_int(&num);
                    } else if (strcmp(key, "seed") == 0) {
                        /* a negative seed is taken modulo 2^64 */
                        msg->start.seed = num.negative ? 0 - num.magnitude : num.magnitude;
                    } else if (strcmp(key, "move_timeout_ms") == 0) {
                        msg->start.move_timeout_ms = to_int(&num);
                    } else if (strcmp(key, "run") == 0) {
                        msg->run = to_int(&num);
                        have_run = 1;
                    } else if (strcmp(key, "step") == 0) {
                        msg->step = to_int(&num);
                    } else if (strcmp(key, "score") == 0) {
                        msg->end.score = num.value;
                        msg->end.has_score = 1;
                    } else if (strcmp(key, "run0_steps") == 0) {
                        msg->end.run0_steps = to_long(&num);
                        msg->end.has_run0_steps = 1;
                    } else {
                        msg->end.run1_steps = to_long(&num);
                        msg->end.has_run1_steps = 1;
                    }
                }
            } else {
                if (skip_value(&r, 0) != 0)
                    goto bad;
            }
            skip_ws(&r);
            if (peek(&r) == ',') {
                r.p++;
                continue;
            }
            if (peek(&r) == '}') {
                r.p++;
                break;
            }
            fail(&r, "expected ',' or '}'");
            goto bad;
        }
    }
    skip_ws(&r);
    if (r.p != r.end) {
        fail(&r, "text after the JSON object");
        goto bad;
    }

    msg->type = MB_MSG_OTHER;
    if (have_type && strcmp(type, "start") == 0) {
        if (!have_dim) {
            fail(&r, "start message without maze_dim");
            goto bad;
        }
        msg->type = MB_MSG_START;
    } else if (have_type && strcmp(type, "sense") == 0) {
        if (!have_run || !have_sensors) {
            fail(&r, "sense message without run or three sensors");
            goto bad;
        }
        msg->type = MB_MSG_SENSE;
    } else if (have_type && strcmp(type, "end") == 0) {
        msg->type = MB_MSG_END;
    }
    return 0;

bad:
    if (err != NULL && errlen > 0) {
        snprintf(err, errlen, "%s at byte %ld", r.why ? r.why : "bad JSON",
                 (long)(r.p - line));
    }
    return -1;
}

/* ------------------------------------------------------------------------ */
/* Debug drawing: a bounded JSON writer and the mb_debug builder.            */

typedef struct writer {
    char *p;
    size_t cap; /* bytes available at p */
    size_t len;
    int full;   /* something did not fit: the text is incomplete */
} writer;

static void w_raw(writer *w, const char *s, size_t n)
{
    if (w->full || n > w->cap - w->len) {
        w->full = 1;
        return;
    }
    memcpy(w->p + w->len, s, n);
    w->len += n;
}

static void w_str(writer *w, const char *s)
{
    w_raw(w, s, strlen(s));
}

static void w_long(writer *w, long v)
{
    char b[32];
    int n = snprintf(b, sizeof b, "%ld", v);
    w_raw(w, b, (size_t)n);
}

/* The length of the valid UTF-8 sequence at s (NUL-terminated), or 0. */
static size_t utf8_len(const unsigned char *s)
{
    unsigned char c = s[0];
    unsigned char lo = 0x80, hi = 0xBF;
    size_t n;
    if (c < 0x80)
        return 1;
    if (c >= 0xC2 && c <= 0xDF)
        n = 2;
    else if (c >= 0xE0 && c <= 0xEF) {
        n = 3;
        if (c == 0xE0)
            lo = 0xA0; /* no overlong forms */
        if (c == 0xED)
            hi = 0x9F; /* no surrogates */
    } else if (c >= 0xF0 && c <= 0xF4) {
        n = 4;
        if (c == 0xF0)
            lo = 0x90;
        if (c == 0xF4)
            hi = 0x8F; /* nothing above U+10FFFF */
    } else
        return 0;
    if (s[1] < lo || s[1] > hi)
        return 0;
    for (size_t i = 2; i < n; i++)
        if (s[i] < 0x80 || s[i] > 0xBF)
            return 0;
    return n;
}

/* Writes s as a JSON string: quotes, backslashes and control characters
 * escaped, bytes that are not UTF-8 replaced by U+FFFD. */
static void w_json_string(writer *w, const char *s)
{
    const unsigned char *u = (const unsigned char *)s;
    w_raw(w, "\"", 1);
    while (*u != 0) {
        size_t n = utf8_len(u);
        if (n == 0) {
            w_str(w, "\\ufffd");
            u++;
        } else if (n > 1) {
            w_raw(w, (const char *)u, n);
            u += n;
        } else {
            char esc[8];
            switch (*u) {
            case '"': w_str(w, "\\\""); break;
            case '\\': w_str(w, "\\\\"); break;
            case '\n': w_str(w, "\\n"); break;
            case '\r': w_str(w, "\\r"); break;
            case '\t': w_str(w, "\\t"); break;
            default:
                if (*u < 0x20 || *u == 0x7F) {
                    snprintf(esc, sizeof esc, "\\u%04x", (unsigned)*u);
                    w_str(w, esc);
                } else {
                    w_raw(w, (const char *)u, 1);
                }
            }
            u++;
        }
    }
    w_raw(w, "\"", 1);
}

static const char *const debug_keys[7] = {"", "text", "walls", "cells", "grid", "colors", "path"};

/* Fields sent as a list of items (the others hold one JSON value each). */
static int is_list(int field)
{
    return field == MB_DEBUG_WALLS || field == MB_DEBUG_CELLS || field == MB_DEBUG_COLORS;
}

/* The size of the object's JSON with these field sizes. */
static unsigned long debug_size(const unsigned long *bytes, const int *count)
{
    unsigned long n = 2;
    int fields = 0;
    for (int f = 1; f <= 6; f++) {
        if (count[f] < 0)
            continue;
        fields++;
        n += strlen(debug_keys[f]) + 3 + bytes[f]; /* "key": */
        if (is_list(f))
            n += 2 + (count[f] > 0 ? (unsigned long)count[f] - 1 : 0);
    }
    return n + (fields > 1 ? (unsigned long)fields - 1 : 0);
}

void mb_debug_clear(mb_debug *d)
{
    d->used = 0;
    d->dropped = 0;
    for (int f = 0; f < 7; f++) {
        d->field_bytes[f] = 0;
        d->field_count[f] = -1;
    }
    d->json[0] = '\0';
}

/* A writer for a new item at the end of d->items (room kept for its tag and NUL). */
static writer item_begin(mb_debug *d)
{
    writer w;
    size_t room = sizeof d->items - d->used;
    w.p = d->items + d->used + 1;
    w.cap = room >= 2 ? room - 2 : 0;
    w.len = 0;
    w.full = room < 2;
    return w;
}

/* Keeps the item written with w as one of field's items (for a one-value
 * field, instead of its earlier value), if the object stays within
 * MB_DEBUG_MAX. Returns 0, or -1 (the item is left out). */
static int item_end(mb_debug *d, int field, const writer *w)
{
    unsigned long bytes[7];
    int count[7];
    memcpy(bytes, d->field_bytes, sizeof bytes);
    memcpy(count, d->field_count, sizeof count);
    if (!is_list(field)) {
        bytes[field] = 0;
        count[field] = 0;
    }
    bytes[field] += w->len;
    count[field] = (count[field] < 0 ? 0 : count[field]) + 1;
    if (w->full || debug_size(bytes, count) > MB_DEBUG_MAX) {
        d->dropped++;
        return -1;
    }
    if (!is_list(field)) { /* the earlier value is dead */
        for (unsigned long i = 0; i < d->used; i += strlen(d->items + i + 1) + 2)
            if (d->items[i] == (char)field)
                d->items[i] = 0;
    }
    d->items[d->used] = (char)field;
    d->items[d->used + 1 + w->len] = '\0';
    d->used += w->len + 2;
    memcpy(d->field_bytes, bytes, sizeof bytes);
    memcpy(d->field_count, count, sizeof count);
    return 0;
}

int mb_debug_text(mb_debug *d, const char *fmt, ...)
{
    char text[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    writer w = item_begin(d);
    w_json_string(&w, text);
    return item_end(d, MB_DEBUG_TEXT, &w);
}

static void w_cell(writer *w, int x, int y)
{
    w_raw(w, "[", 1);
    w_long(w, x);
    w_raw(w, ",", 1);
    w_long(w, y);
}

int mb_debug_wall(mb_debug *d, int x, int y, int side)
{
    static const char *const names[4] = {",\"up\"]", ",\"right\"]", ",\"down\"]", ",\"left\"]"};
    if (side < 0 || side > 3) {
        d->dropped++;
        return -1;
    }
    writer w = item_begin(d);
    w_cell(&w, x, y);
    w_str(&w, names[side]);
    return item_end(d, MB_DEBUG_WALLS, &w);
}

int mb_debug_cell_int(mb_debug *d, int x, int y, long value)
{
    writer w = item_begin(d);
    w_cell(&w, x, y);
    w_raw(&w, ",", 1);
    w_long(&w, value);
    w_raw(&w, "]", 1);
    return item_end(d, MB_DEBUG_CELLS, &w);
}

int mb_debug_cell_text(mb_debug *d, int x, int y, const char *text)
{
    writer w = item_begin(d);
    w_cell(&w, x, y);
    w_raw(&w, ",", 1);
    w_json_string(&w, text != NULL ? text : "");
    w_raw(&w, "]", 1);
    return item_end(d, MB_DEBUG_CELLS, &w);
}

int mb_debug_grid(mb_debug *d, int n, const int *values, int null_value)
{
    if (n < 0 || (n > 0 && values == NULL)) {
        d->dropped++;
        return -1;
    }
    writer w = item_begin(d);
    w_raw(&w, "[", 1);
    for (int x = 0; x < n && !w.full; x++) {
        w_str(&w, x == 0 ? "[" : ",[");
        for (int y = 0; y < n; y++) {
            int v = values[(size_t)x * (size_t)n + (size_t)y];
            if (y > 0)
                w_raw(&w, ",", 1);
            if (v == null_value)
                w_str(&w, "null");
            else
                w_long(&w, v);
        }
        w_raw(&w, "]", 1);
    }
    w_raw(&w, "]", 1);
    return item_end(d, MB_DEBUG_GRID, &w);
}

int mb_debug_color(mb_debug *d, int x, int y, const char *hex)
{
    size_t n = hex != NULL ? strlen(hex) : 0;
    int ok = (n == 4 || n == 7) && hex[0] == '#';
    for (size_t i = 1; ok && i < n; i++) {
        char c = hex[i];
        ok = (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
    }
    if (!ok) {
        d->dropped++;
        return -1;
    }
    writer w = item_begin(d);
    w_cell(&w, x, y);
    w_str(&w, ",\"");
    w_str(&w, hex);
    w_str(&w, "\"]");
    return item_end(d, MB_DEBUG_COLORS, &w);
}

int mb_debug_path(mb_debug *d, int count, const int *xy)
{
    if (count < 0 || (count > 0 && xy == NULL)) {
        d->dropped++;
        return -1;
    }
    writer w = item_begin(d);
    w_raw(&w, "[", 1);
    for (int i = 0; i < count && !w.full; i++) {
        if (i > 0)
            w_raw(&w, ",", 1);
        w_cell(&w, xy[2 * i], xy[2 * i + 1]);
        w_raw(&w, "]", 1);
    }
    w_raw(&w, "]", 1);
    return item_end(d, MB_DEBUG_PATH, &w);
}

int mb_debug_empty(mb_debug *d, enum mb_debug_field field)
{
    int f = (int)field;
    if (f < MB_DEBUG_TEXT || f > MB_DEBUG_PATH) {
        d->dropped++;
        return -1;
    }
    if (!is_list(f)) {
        writer w = item_begin(d);
        w_str(&w, f == MB_DEBUG_TEXT ? "\"\"" : "[]");
        return item_end(d, f, &w);
    }
    unsigned long bytes[7];
    int count[7];
    memcpy(bytes, d->field_bytes, sizeof bytes);
    memcpy(count, d->field_count, sizeof count);
    bytes[f] = 0;
    count[f] = 0;
    if (debug_size(bytes, count) > MB_DEBUG_MAX) {
        d->dropped++;
        return -1;
    }
    for (unsigned long i = 0; i < d->used; i += strlen(d->items + i + 1) + 2)
        if (d->items[i] == (char)f)
            d->items[i] = 0;
    d->field_bytes[f] = 0;
    d->field_count[f] = 0;
    return 0;
}

const char *mb_debug_json(mb_debug *d)
{
    writer w = {d->json, sizeof d->json - 1, 0, 0};
    int fields = 0;
    for (int f = 1; f <= 6; f++) {
        int items = 0;
        if (d->field_count[f] < 0)
            continue;
        w_str(&w, fields++ > 0 ? ",\"" : "{\"");
        w_str(&w, debug_keys[f]);
        w_str(&w, "\":");
        if (is_list(f))
            w_raw(&w, "[", 1);
        for (unsigned long i = 0; i < d->used; i += strlen(d->items + i + 1) + 2) {
            if (d->items[i] != (char)f)
                continue;
            if (items++ > 0)
                w_raw(&w, ",", 1);
            w_str(&w, d->items + i + 1);
        }
        if (is_list(f))
            w_raw(&w, "]", 1);
    }
    if (fields == 0 || w.full) /* full: cannot happen, the items are kept within bounds */
        return NULL;
    w_raw(&w, "}", 1);
    d->json[w.len] = '\0';
    return d->json;
}

/* The debug object's text to send with the answer being returned, if any. */
static const char *pending_debug;

mb_answer mb_with_debug(mb_answer a, mb_debug *d)
{
    pending_debug = d != NULL ? mb_debug_json(d) : NULL;
    return a;
}

mb_answer mb_with_debug_json(mb_answer a, const char *json)
{
    pending_debug = json;
    return a;
}

/* Why `json` cannot be sent as a debug object, or NULL if it can. */
static const char *debug_problem(const char *json, size_t len)
{
    reader r = {json, json + len, NULL};
    for (const unsigned char *u = (const unsigned char *)json; *u != 0;) {
        size_t n = utf8_len(u);
        if (n == 0)
            return "not UTF-8";
        u += n;
    }
    skip_ws(&r);
    if (peek(&r) != '{')
        return "not a JSON object";
    if (skip_value(&r, 0) != 0)
        return r.why != NULL ? r.why : "bad JSON";
    skip_ws(&r);
    if (r.p != r.end)
        return "text after the JSON object";
    return NULL;
}

/* ------------------------------------------------------------------------ */
/* The conversation.                                                         */

/* Private copies of the real stdin/stdout; fd 0 -> /dev/null, fd 1 -> stderr. */
static void private_stdio(FILE **in, FILE **out)
{
    int in_fd, out_fd, devnull;

    *in = stdin;
    *out = stdout;
    in_fd = dup(0);
    out_fd = dup(1);
    if (in_fd < 0 || out_fd < 0) {
        if (in_fd >= 0)
            close(in_fd);
        if (out_fd >= 0)
            close(out_fd);
        return; /* keep the plain streams */
    }
    FILE *pin = fdopen(in_fd, "rb");
    FILE *pout = fdopen(out_fd, "wb");
    if (pin == NULL || pout == NULL) {
        if (pin != NULL)
            fclose(pin);
        else
            close(in_fd);
        if (pout != NULL)
            fclose(pout);
        else
            close(out_fd);
        return;
    }
    *in = pin;
    *out = pout;
    if (dup2(2, 1) >= 0) {
        /* Text printed before mb_run and still buffered goes to the log, not to the
         * protocol channel, where the server would take it for an answer. */
        fflush(stdout);
        setvbuf(stdout, NULL, _IOLBF, 0); /* the log, line by line */
    }
    devnull = open("/dev/null", O_RDONLY);
    if (devnull >= 0) {
        dup2(devnull, 0);
        if (devnull != 0)
            close(devnull);
    }
}

static void log_line(const char *what, const char *line, size_t len)
{
    fprintf(stderr, "mazebot: %s: %.*s%s\n", what, (int)(len > 200 ? 200 : len), line,
            len > 200 ? "..." : "");
    fflush(stderr);
}

int mb_run(const mb_bot *bot)
{
    FILE *in, *out;
    char *line;
    int status = 0;
    unsigned long debug_sent = 0;
    int warned_bad = 0, warned_step = 0, warned_match = 0;

    if (bot == NULL || bot->next_move == NULL) {
        fprintf(stderr, "mazebot: mb_run needs a bot with a next_move callback\n");
        return 1;
    }
#ifdef SIGPIPE
    signal(SIGPIPE, SIG_IGN); /* a closed pipe is an error from fwrite, not a signal */
#endif
    line = malloc(MB_MAX_LINE + 1);
    if (line == NULL) {
        fprintf(stderr, "mazebot: out of memory\n");
        return 1;
    }
    private_stdio(&in, &out);

    for (;;) {
        size_t len = 0;
        int c, too_long = 0;
        mb_message msg;
        char err[128];

        while ((c = getc(in)) != EOF && c != '\n') {
            if (len < MB_MAX_LINE)
                line[len++] = (char)c;
            else
                too_long = 1;
        }
        if (c == EOF && len == 0)
            break; /* the server closed our stdin */
        if (too_long) {
            log_line("ignored a line longer than 64 KiB", line, len);
            continue;
        }
        while (len > 0 && (line[len - 1] == '\r' || line[len - 1] == ' ' ||
                           line[len - 1] == '\t'))
            len--;
        if (len == 0)
            continue;
        if (mb_parse_message(line, len, &msg, err, sizeof err) != 0) {
            char what[160];
            snprintf(what, sizeof what, "cannot read a message (%s)", err);
            log_line(what, line, len);
            status = 1;
            break;
        }
        if (msg.type == MB_MSG_START) {
            if (bot->start != NULL)
                bot->start(bot->user, &msg.start);
        } else if (msg.type == MB_MSG_SENSE) {
            const char *debug, *problem;
            size_t debug_len;
            pending_debug = NULL;
            mb_answer a = bot->next_move(bot->user, msg.sensors, msg.run, msg.step);
            debug = pending_debug;
            pending_debug = NULL;
            if (debug != NULL) {
                debug_len = strlen(debug);
                if (debug_len > MB_DEBUG_MAX) {
                    if (!warned_step++)
                        fprintf(stderr, "mazebot: step %d: debug object of %lu bytes, over %d: not sent\n",
                                msg.step, (unsigned long)debug_len, MB_DEBUG_MAX);
                    debug = NULL;
                } else if ((problem = debug_problem(debug, debug_len)) != NULL) {
                    if (!warned_bad++)
                        fprintf(stderr, "mazebot: step %d: debug object not sent (%s)\n", msg.step,
                                problem);
                    debug = NULL;
                } else if (debug_sent + debug_len > MB_DEBUG_MATCH_MAX) {
                    if (!warned_match++)
                        fprintf(stderr,
                                "mazebot: step %d: the match's debug objects reached %d bytes: "
                                "no more are sent\n",
                                msg.step, MB_DEBUG_MATCH_MAX);
                    debug = NULL;
                } else {
                    debug_sent += debug_len;
                }
            }
            if (a.reset)
                fputs("{\"reset\":true", out);
            else
                fprintf(out, "{\"rotation\":%d,\"movement\":%d", a.rotation, a.movement);
            if (debug != NULL) {
                /* A valid object has line breaks only between its tokens (a string
                 * holds them escaped): written as spaces, it stays one line. */
                fputs(",\"debug\":", out);
                for (const char *p = debug; *p != 0; p++)
                    putc(*p == '\n' || *p == '\r' ? ' ' : *p, out);
            }
            fputs("}\n", out);
            if (fflush(out) != 0 || ferror(out))
                break; /* the server stopped listening: nothing left to do */
        } else if (msg.type == MB_MSG_END) {
            if (bot->end != NULL)
                bot->end(bot->user, &msg.end);
            break;
        }
        /* other message types: ignored (room for later protocol versions) */
        if (c == EOF)
            break;
    }
    free(line);
    fflush(stdout);
    fflush(stderr);
    if (in != stdin)
        fclose(in);
    if (out != stdout)
        fclose(out);
    return status;
}
