// mazebot.cpp: protocol v1 for C++ bots (see mazebot.hpp and docs/PROTOCOL.md).
//
// Reads the server's messages line by line, parses them with a small JSON
// reader (any field order, any whitespace, unknown fields of any type
// skipped), calls the bot's callbacks and writes one JSON line per answer,
// straight to the file descriptor. Also the Debug builder, a bounded JSON
// writer. Only the C++17 standard library and POSIX (dup, dup2, open, read,
// write) are used.
#include "mazebot.hpp"

#include <cerrno>
#include <climits>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#include <locale>
#include <sstream>

#include <fcntl.h>
#include <unistd.h>

namespace mazebot {

namespace {

// ------------------------------------------------------------------------
// A tiny JSON reader over one line.

constexpr int kMaxDepth = 200; // nesting accepted inside skipped values

// A JSON number: its value as a double and, when it is written as an integer,
// as a sign and a magnitude saturated at UINT64_MAX.
struct Number {
    double value = 0;
    bool is_integer = true;
    bool negative = false;
    std::uint64_t magnitude = 0;
};

bool is_digit(int c)
{
    return c >= '0' && c <= '9';
}

class Reader {
public:
    explicit Reader(std::string_view s) : begin_(s.data()), p_(s.data()), end_(s.data() + s.size()) {}

    const char* why() const { return why_; }
    std::size_t offset() const { return static_cast<std::size_t>(p_ - begin_); }
    bool at_end() const { return p_ == end_; }

    bool fail(const char* why)
    {
        if (why_ == nullptr)
            why_ = why;
        return false;
    }

    void skip_ws()
    {
        while (p_ < end_ && (*p_ == ' ' || *p_ == '\t' || *p_ == '\n' || *p_ == '\r'))
            p_++;
    }

    int peek() const { return p_ < end_ ? static_cast<unsigned char>(*p_) : -1; }

    // Consumes c if it is next.
    bool eat(char c)
    {
        if (peek() != static_cast<unsigned char>(c))
            return false;
        p_++;
        return true;
    }

    bool expect_word(std::string_view word)
    {
        if (static_cast<std::size_t>(end_ - p_) < word.size() ||
            std::string_view(p_, word.size()) != word)
            return fail("unexpected character");
        p_ += word.size();
        return true;
    }

    // Reads a string; its decoded text goes to out if not null.
    bool read_string(std::string* out)
    {
        if (out != nullptr)
            out->clear();
        if (!eat('"'))
            return fail("expected a string");
        for (;;) {
            if (p_ >= end_)
                return fail("unterminated string");
            unsigned char c = static_cast<unsigned char>(*p_++);
            if (c == '"')
                return true;
            if (c < 0x20)
                return fail("control character in a string");
            if (c != '\\') {
                if (out != nullptr)
                    out->push_back(static_cast<char>(c));
                continue;
            }
            if (p_ >= end_)
                return fail("unterminated string");
            c = static_cast<unsigned char>(*p_++);
            char plain = 0;
            switch (c) {
            case '"': plain = '"'; break;
            case '\\': plain = '\\'; break;
            case '/': plain = '/'; break;
            case 'b': plain = '\b'; break;
            case 'f': plain = '\f'; break;
            case 'n': plain = '\n'; break;
            case 'r': plain = '\r'; break;
            case 't': plain = '\t'; break;
            case 'u': {
                unsigned cp = 0;
                if (!hex4(cp))
                    return false;
                if (cp >= 0xD800 && cp < 0xDC00 && end_ - p_ >= 6 && p_[0] == '\\' && p_[1] == 'u') {
                    const char* save = p_;
                    unsigned lo = 0;
                    p_ += 2;
                    if (hex4(lo) && lo >= 0xDC00 && lo < 0xE000) {
                        cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
                    } else { // not a low surrogate: leave it for the next round
                        p_ = save;
                        why_ = nullptr;
                        cp = 0xFFFD;
                    }
                } else if (cp >= 0xD800 && cp < 0xE000) {
                    cp = 0xFFFD; // a lone surrogate
                }
                if (out != nullptr)
                    put_utf8(*out, cp);
                continue;
            }
            default:
                return fail("bad escape in a string");
            }
            if (out != nullptr)
                out->push_back(plain);
        }
    }

    bool read_number(Number& out)
    {
        const char* start = p_;
        out = Number{};
        if (eat('-'))
            out.negative = true;
        if (!is_digit(peek()))
            return fail("bad number");
        if (!eat('0')) {
            while (is_digit(peek())) {
                unsigned d = static_cast<unsigned>(*p_++ - '0');
                if (out.magnitude > (UINT64_MAX - d) / 10)
                    out.magnitude = UINT64_MAX;
                else
                    out.magnitude = out.magnitude * 10 + d;
            }
        }
        if (eat('.')) {
            out.is_integer = false;
            if (!is_digit(peek()))
                return fail("bad number");
            while (is_digit(peek()))
                p_++;
        }
        if (peek() == 'e' || peek() == 'E') {
            out.is_integer = false;
            p_++;
            if (peek() == '+' || peek() == '-')
                p_++;
            if (!is_digit(peek()))
                return fail("bad number");
            while (is_digit(peek()))
                p_++;
        }
        if (out.is_integer && out.magnitude != UINT64_MAX) { // the common case, exact up to 2^53
            out.value = static_cast<double>(out.magnitude);
            if (out.negative)
                out.value = -out.value;
        } else { // the classic locale: "." whatever the program's locale
            std::istringstream in(std::string(start, p_));
            in.imbue(std::locale::classic());
            in >> out.value; // out of range (1e999): the largest double, or 0
        }
        return true;
    }

    bool skip_value(int depth)
    {
        Number num;
        if (depth > kMaxDepth)
            return fail("nested too deeply");
        switch (peek()) {
        case '{': return skip_container(depth, '}', true);
        case '[': return skip_container(depth, ']', false);
        case '"': return read_string(nullptr);
        case 't': return expect_word("true");
        case 'f': return expect_word("false");
        case 'n': return expect_word("null");
        default:
            if (peek() == '-' || is_digit(peek()))
                return read_number(num);
            return fail("expected a value");
        }
    }

    // Reads a number or null (is_null set). Returns 1, 0 for a value of another
    // type (skipped: treated as absent), or -1 on bad JSON.
    int read_number_or_null(Number& n, bool& is_null)
    {
        is_null = false;
        if (peek() == 'n') {
            is_null = true;
            return expect_word("null") ? 1 : -1;
        }
        if (peek() == '-' || is_digit(peek()))
            return read_number(n) ? 1 : -1;
        return skip_value(0) ? 0 : -1;
    }

private:
    bool hex4(unsigned& out)
    {
        unsigned v = 0;
        if (end_ - p_ < 4)
            return fail("short \\u escape");
        for (int i = 0; i < 4; i++) {
            int c = static_cast<unsigned char>(p_[i]);
            v <<= 4;
            if (c >= '0' && c <= '9')
                v |= static_cast<unsigned>(c - '0');
            else if (c >= 'a' && c <= 'f')
                v |= static_cast<unsigned>(c - 'a' + 10);
            else if (c >= 'A' && c <= 'F')
                v |= static_cast<unsigned>(c - 'A' + 10);
            else
                return fail("bad \\u escape");
        }
        p_ += 4;
        out = v;
        return true;
    }

    static void put_utf8(std::string& out, unsigned cp)
    {
        if (cp < 0x80) {
            out.push_back(static_cast<char>(cp));
        } else if (cp < 0x800) {
            out.push_back(static_cast<char>(0xC0 | (cp >> 6)));
            out.push_back(static_cast<char>(0x80 | (cp & 0x3F)));
        } else if (cp < 0x10000) {
            out.push_back(static_cast<char>(0xE0 | (cp >> 12)));
            out.push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
            out.push_back(static_cast<char>(0x80 | (cp & 0x3F)));
        } else {
            out.push_back(static_cast<char>(0xF0 | (cp >> 18)));
            out.push_back(static_cast<char>(0x80 | ((cp >> 12) & 0x3F)));
            out.push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
            out.push_back(static_cast<char>(0x80 | (cp & 0x3F)));
        }
    }

    bool skip_container(int depth, char close, bool object)
    {
        p_++; // the opening bracket
        skip_ws();
        if (eat(close))
            return true;
        for (;;) {
            skip_ws();
            if (object) {
                if (!read_string(nullptr))
                    return false;
                skip_ws();
                if (!eat(':'))
                    return fail("expected ':'");
                skip_ws();
            }
            if (!skip_value(depth + 1))
                return false;
            skip_ws();
            if (eat(','))
                continue;
            if (eat(close))
                return true;
            return fail(object ? "expected ',' or '}'" : "expected ',' or ']'");
        }
    }

    const char* begin_;
    const char* p_;
    const char* end_;
    const char* why_ = nullptr; // the first error
};

// Clamps a number to T's range (rounding toward zero).
template <typename T>
T clamp_to(const Number& n, T lo, T hi)
{
    if (n.is_integer) {
        if (n.negative)
            return n.magnitude > static_cast<std::uint64_t>(hi) ? lo
                                                                : static_cast<T>(-static_cast<T>(n.magnitude));
        return n.magnitude > static_cast<std::uint64_t>(hi) ? hi : static_cast<T>(n.magnitude);
    }
    if (std::isnan(n.value))
        return 0;
    if (n.value >= static_cast<double>(hi))
        return hi;
    if (n.value <= static_cast<double>(lo))
        return lo;
    return static_cast<T>(n.value);
}

int to_int(const Number& n)
{
    return clamp_to<int>(n, INT_MIN, INT_MAX);
}

long long to_long(const Number& n)
{
    return clamp_to<long long>(n, LLONG_MIN, LLONG_MAX);
}

// ------------------------------------------------------------------------
// UTF-8 and JSON strings.

// The length of the valid UTF-8 sequence at s[i], or 0.
std::size_t utf8_len(std::string_view s, std::size_t i)
{
    unsigned char c = static_cast<unsigned char>(s[i]);
    unsigned char lo = 0x80, hi = 0xBF;
    std::size_t n;
    if (c < 0x80)
        return 1;
    if (c >= 0xC2 && c <= 0xDF) {
        n = 2;
    } else if (c >= 0xE0 && c <= 0xEF) {
        n = 3;
        if (c == 0xE0)
            lo = 0xA0; // no overlong forms
        if (c == 0xED)
            hi = 0x9F; // no surrogates
    } else if (c >= 0xF0 && c <= 0xF4) {
        n = 4;
        if (c == 0xF0)
            lo = 0x90;
        if (c == 0xF4)
            hi = 0x8F; // nothing above U+10FFFF
    } else {
        return 0;
    }
    if (s.size() - i < n)
        return 0;
    unsigned char c1 = static_cast<unsigned char>(s[i + 1]);
    if (c1 < lo || c1 > hi)
        return 0;
    for (std::size_t k = 2; k < n; k++) {
        unsigned char ck = static_cast<unsigned char>(s[i + k]);
        if (ck < 0x80 || ck > 0xBF)
            return 0;
    }
    return n;
}

// Appends s as a JSON string: quotes, backslashes and control characters
// escaped, bytes that are not UTF-8 replaced by U+FFFD.
void append_json_string(std::string& out, std::string_view s)
{
    out.push_back('"');
    for (std::size_t i = 0; i < s.size();) {
        std::size_t n = utf8_len(s, i);
        if (n == 0) {
            out += "\\ufffd";
            i++;
            continue;
        }
        if (n > 1) {
            out.append(s.data() + i, n);
            i += n;
            continue;
        }
        unsigned char c = static_cast<unsigned char>(s[i++]);
        switch (c) {
        case '"': out += "\\\""; break;
        case '\\': out += "\\\\"; break;
        case '\n': out += "\\n"; break;
        case '\r': out += "\\r"; break;
        case '\t': out += "\\t"; break;
        default:
            if (c < 0x20 || c == 0x7F) {
                char esc[8];
                std::snprintf(esc, sizeof esc, "\\u%04x", static_cast<unsigned>(c));
                out += esc;
            } else {
                out.push_back(static_cast<char>(c));
            }
        }
    }
    out.push_back('"');
}

void append_cell(std::string& out, int x, int y)
{
    out.push_back('[');
    out += std::to_string(x);
    out.push_back(',');
    out += std::to_string(y);
}

const char* const kDebugKeys[6] = {"text", "walls", "cells", "grid", "colors", "path"};

// Fields sent as a list of items (the others hold one JSON value each).
bool is_list(Field f)
{
    return f == Field::Walls || f == Field::Cells || f == Field::Colors;
}

} // namespace

// ------------------------------------------------------------------------
// Parsing messages.

bool parse_message(std::string_view line, Message& msg, std::string* error)
{
    Reader r(line);
    std::string type, key;
    bool have_type = false, have_dim = false, have_run = false, have_sensors = false;
    msg = Message{};
    if (error != nullptr)
        error->clear();

    auto bad = [&](const char* why) {
        r.fail(why);
        if (error != nullptr)
            *error = std::string(r.why()) + " at byte " + std::to_string(r.offset());
        return false;
    };

    r.skip_ws();
    if (!r.eat('{'))
        return bad("not a JSON object");
    r.skip_ws();
    if (!r.eat('}')) {
        for (;;) {
            Number num;
            bool is_null = false;
            r.skip_ws();
            if (!r.read_string(&key))
                return bad("bad JSON");
            r.skip_ws();
            if (!r.eat(':'))
                return bad("expected ':'");
            r.skip_ws();
            if (key == "type" && r.peek() == '"') {
                if (!r.read_string(&type))
                    return bad("bad JSON");
                have_type = true;
            } else if (key == "status" && r.peek() == '"') {
                if (!r.read_string(&msg.end.status))
                    return bad("bad JSON");
            } else if (key == "sensors" && r.peek() == '[') {
                int count = 0;
                r.eat('[');
                r.skip_ws();
                if (!r.eat(']')) {
                    for (;;) {
                        r.skip_ws();
                        int rc = r.read_number_or_null(num, is_null);
                        if (rc < 0)
                            return bad("bad JSON");
                        if (rc > 0 && !is_null && count < 3)
                            msg.sensors[static_cast<std::size_t>(count)] = to_int(num);
                        count++;
                        r.skip_ws();
                        if (r.eat(','))
                            continue;
                        if (r.eat(']'))
                            break;
                        return bad("expected ',' or ']'");
                    }
                }
                have_sensors = count == 3;
            } else if (key == "protocol" || key == "maze_dim" || key == "max_steps" ||
                       key == "seed" || key == "move_timeout_ms" || key == "run" ||
                       key == "step" || key == "score" || key == "run0_steps" ||
                       key == "run1_steps") {
                int rc = r.read_number_or_null(num, is_null);
                if (rc < 0)
                    return bad("bad JSON");
                if (rc > 0 && !is_null) {
                    if (key == "protocol") {
                        msg.start.protocol = to_int(num);
                    } else if (key == "maze_dim") {
                        msg.start.maze_dim = to_int(num);
                        have_dim = true;
                    } else if (key == "max_steps") {
                        msg.start.max_steps = to_int(num);
                    } else if (key == "seed") { // a negative seed is taken modulo 2^64
                        msg.start.seed = num.negative ? 0 - num.magnitude : num.magnitude;
                    } else if (key == "move_timeout_ms") {
                        msg.start.move_timeout_ms = to_int(num);
                    } else if (key == "run") {
                        msg.run = to_int(num);
                        have_run = true;
                    } else if (key == "step") {
                        msg.step = to_int(num);
                    } else if (key == "score") {
                        msg.end.score = num.value;
                    } else if (key == "run0_steps") {
                        msg.end.run0_steps = to_long(num);
                    } else {
                        msg.end.run1_steps = to_long(num);
                    }
                }
            } else if (!r.skip_value(0)) {
                return bad("bad JSON");
            }
            r.skip_ws();
            if (r.eat(','))
                continue;
            if (r.eat('}'))
                break;
            return bad("expected ',' or '}'");
        }
    }
    r.skip_ws();
    if (!r.at_end())
        return bad("text after the JSON object");

    msg.type = Message::Type::Other;
    if (have_type && type == "start") {
        if (!have_dim)
            return bad("start message without maze_dim");
        msg.type = Message::Type::Start;
    } else if (have_type && type == "sense") {
        if (!have_run || !have_sensors)
            return bad("sense message without run or three sensors");
        msg.type = Message::Type::Sense;
    } else if (have_type && type == "end") {
        msg.type = Message::Type::End;
    }
    return true;
}

std::string debug_problem(std::string_view json)
{
    for (std::size_t i = 0; i < json.size();) {
        std::size_t n = utf8_len(json, i);
        if (n == 0)
            return "not UTF-8";
        i += n;
    }
    Reader r(json);
    r.skip_ws();
    if (r.peek() != '{')
        return "not a JSON object";
    if (!r.skip_value(0))
        return r.why() != nullptr ? r.why() : "bad JSON";
    r.skip_ws();
    if (!r.at_end())
        return "text after the JSON object";
    return "";
}

// ------------------------------------------------------------------------
// Answers and the Debug builder.

Answer Answer::with_debug(const Debug& d) const
{
    Answer a = *this;
    a.debug = d.json();
    return a;
}

Answer Answer::with_debug_json(std::string json) const
{
    Answer a = *this;
    a.debug = std::move(json);
    return a;
}

void Debug::clear()
{
    fields_ = {};
    dropped_ = 0;
}

// The size of the object's JSON if field f had `count` items of `bytes` bytes
// in all (present = false: f absent), the other fields as they are.
std::size_t Debug::size_with(Field f, bool present, std::size_t count, std::size_t bytes) const
{
    std::size_t n = 2; // {}
    int fields = 0;
    for (int i = 0; i < kFields; i++) {
        const Slot& s = fields_[static_cast<std::size_t>(i)];
        bool here = i == static_cast<int>(f);
        std::size_t c = here ? count : s.items.size(), b = here ? bytes : s.bytes;
        if (!(here ? present : s.present))
            continue;
        fields++;
        n += std::strlen(kDebugKeys[i]) + 3 + b; // "key":
        if (is_list(static_cast<Field>(i)))
            n += 2 + (c > 0 ? c - 1 : 0); // [ , ]
    }
    return n + (fields > 1 ? static_cast<std::size_t>(fields) - 1 : 0);
}

// Keeps item as one of field's items (for a one-value field, instead of its
// earlier value) if the object stays within kDebugMax bytes.
bool Debug::add(Field field, std::string item)
{
    Slot& s = fields_[static_cast<std::size_t>(field)];
    bool list = is_list(field);
    std::size_t count = list ? s.items.size() + 1 : 1;
    std::size_t bytes = (list ? s.bytes : 0) + item.size();
    if (size_with(field, true, count, bytes) > kDebugMax) {
        dropped_++;
        return false;
    }
    if (!list)
        s.items.clear();
    s.present = true;
    s.bytes = bytes;
    s.items.push_back(std::move(item));
    return true;
}

bool Debug::text(std::string_view s)
{
    constexpr std::size_t kMaxText = 4096;
    if (s.size() > kMaxText) { // cut at a character boundary
        std::size_t cut = kMaxText;
        while (cut > 0 && (static_cast<unsigned char>(s[cut]) & 0xC0) == 0x80)
            cut--;
        s = s.substr(0, cut);
    }
    std::string item;
    append_json_string(item, s);
    return add(Field::Text, std::move(item));
}

bool Debug::wall(int x, int y, Side side)
{
    static const char* const names[4] = {",\"up\"]", ",\"right\"]", ",\"down\"]", ",\"left\"]"};
    int i = static_cast<int>(side);
    if (i < 0 || i > 3) {
        dropped_++;
        return false;
    }
    std::string item;
    append_cell(item, x, y);
    item += names[i];
    return add(Field::Walls, std::move(item));
}

bool Debug::cell(int x, int y, long long value)
{
    std::string item;
    append_cell(item, x, y);
    item.push_back(',');
    item += std::to_string(value);
    item.push_back(']');
    return add(Field::Cells, std::move(item));
}

bool Debug::cell(int x, int y, std::string_view text)
{
    std::string item;
    append_cell(item, x, y);
    item.push_back(',');
    append_json_string(item, text);
    item.push_back(']');
    return add(Field::Cells, std::move(item));
}

bool Debug::grid(int n, const int* values, int null_value)
{
    if (n < 0 || (n > 0 && values == nullptr) || n > 4096) {
        dropped_++;
        return false;
    }
    std::string item = "[";
    for (int x = 0; x < n && item.size() <= kDebugMax; x++) {
        item += x == 0 ? "[" : ",[";
        for (int y = 0; y < n; y++) {
            int v = values[static_cast<std::size_t>(x) * static_cast<std::size_t>(n) +
                           static_cast<std::size_t>(y)];
            if (y > 0)
                item.push_back(',');
            if (v == null_value)
                item += "null";
            else
                item += std::to_string(v);
        }
        item.push_back(']');
    }
    item.push_back(']'); // when cut short above, it is too big anyway: dropped
    return add(Field::Grid, std::move(item));
}

bool Debug::grid(int n, const std::vector<int>& values, int null_value)
{
    if (n < 0 || values.size() < static_cast<std::size_t>(n) * static_cast<std::size_t>(n)) {
        dropped_++;
        return false;
    }
    return grid(n, values.data(), null_value);
}

bool Debug::color(int x, int y, std::string_view hex)
{
    bool ok = (hex.size() == 4 || hex.size() == 7) && hex[0] == '#';
    for (std::size_t i = 1; ok && i < hex.size(); i++) {
        char c = hex[i];
        ok = (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
    }
    if (!ok) {
        dropped_++;
        return false;
    }
    std::string item;
    append_cell(item, x, y);
    item += ",\"";
    item += hex;
    item += "\"]";
    return add(Field::Colors, std::move(item));
}

bool Debug::path(const std::vector<std::pair<int, int>>& cells)
{
    std::string item = "[";
    for (std::size_t i = 0; i < cells.size() && item.size() <= kDebugMax; i++) {
        if (i > 0)
            item.push_back(',');
        append_cell(item, cells[i].first, cells[i].second);
        item.push_back(']');
    }
    item.push_back(']'); // when cut short above, it is too big anyway: dropped
    return add(Field::Path, std::move(item));
}

bool Debug::empty(Field field)
{
    int f = static_cast<int>(field);
    if (f < 0 || f >= kFields) {
        dropped_++;
        return false;
    }
    if (!is_list(field))
        return add(field, field == Field::Text ? "\"\"" : "[]");
    if (size_with(field, true, 0, 0) > kDebugMax) {
        dropped_++;
        return false;
    }
    fields_[static_cast<std::size_t>(f)] = Slot{true, {}, 0};
    return true;
}

bool Debug::any() const
{
    for (const Slot& s : fields_)
        if (s.present)
            return true;
    return false;
}

std::size_t Debug::size() const
{
    const Slot& t = fields_[0];
    return any() ? size_with(Field::Text, t.present, t.items.size(), t.bytes) : 0;
}

std::string Debug::json() const
{
    if (!any())
        return "";
    std::string out;
    out.reserve(size());
    for (int f = 0; f < kFields; f++) {
        const Slot& s = fields_[static_cast<std::size_t>(f)];
        bool list = is_list(static_cast<Field>(f));
        if (!s.present)
            continue;
        out += out.empty() ? "{\"" : ",\"";
        out += kDebugKeys[f];
        out += "\":";
        if (list)
            out.push_back('[');
        for (std::size_t i = 0; i < s.items.size(); i++) {
            if (i > 0)
                out.push_back(',');
            out += s.items[i];
        }
        if (list)
            out.push_back(']');
    }
    out.push_back('}');
    return out;
}

// ------------------------------------------------------------------------
// The conversation.

namespace {

// Reads lines from a file descriptor, lines longer than kMaxLine reported
// (and their first kMaxLine bytes kept) rather than stored whole.
class LineReader {
public:
    enum class Result { Line, TooLong, End };

    explicit LineReader(int fd) : fd_(fd) {}

    Result next(std::string& line)
    {
        bool too_long = false, any = false;
        line.clear();
        for (;;) {
            if (pos_ == len_) {
                if (eof_)
                    return !any ? Result::End : too_long ? Result::TooLong : Result::Line;
                ssize_t n = ::read(fd_, buf_, sizeof buf_);
                if (n < 0 && errno == EINTR)
                    continue;
                if (n <= 0) {
                    eof_ = true;
                    continue;
                }
                pos_ = 0;
                len_ = static_cast<std::size_t>(n);
            }
            any = true;
            const char* start = buf_ + pos_;
            const void* nl = std::memchr(start, '\n', len_ - pos_);
            std::size_t take = nl != nullptr ? static_cast<std::size_t>(static_cast<const char*>(nl) - start)
                                             : len_ - pos_;
            std::size_t room = kMaxLine - line.size();
            if (take > room)
                too_long = true;
            line.append(start, take < room ? take : room);
            pos_ += take;
            if (nl != nullptr) {
                pos_++; // the "\n"
                return too_long ? Result::TooLong : Result::Line;
            }
        }
    }

private:
    int fd_;
    char buf_[65536];
    std::size_t pos_ = 0, len_ = 0;
    bool eof_ = false;
};

// Writes all of s to fd. False when the server stopped reading.
bool write_all(int fd, const std::string& s)
{
    std::size_t done = 0;
    while (done < s.size()) {
        ssize_t n = ::write(fd, s.data() + done, s.size() - done);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return false;
        done += static_cast<std::size_t>(n);
    }
    return true;
}

void log_line(const std::string& what, std::string_view line)
{
    std::cerr << "mazebot: " << what << ": " << line.substr(0, 200)
              << (line.size() > 200 ? "..." : "") << std::endl;
}

// Private copies of the real stdin/stdout; fd 0 -> /dev/null, fd 1 -> stderr.
// Output the bot printed before run() and left in a buffer goes to stderr too.
void private_stdio(int& in_fd, int& out_fd)
{
    in_fd = 0;
    out_fd = 1;
    int in_copy = ::dup(0);
    int out_copy = ::dup(1);
    if (in_copy < 0 || out_copy < 0) { // keep the plain descriptors
        if (in_copy >= 0)
            ::close(in_copy);
        if (out_copy >= 0)
            ::close(out_copy);
        std::cout.flush();
        std::fflush(stdout);
        return;
    }
    in_fd = in_copy;
    out_fd = out_copy;
    if (::dup2(2, 1) >= 0)
        std::setvbuf(stdout, nullptr, _IOLBF, 0); // the log, line by line
    std::cout.flush(); // what was buffered goes to the log, not to the server
    std::fflush(stdout);
    int devnull = ::open("/dev/null", O_RDONLY);
    if (devnull >= 0) {
        ::dup2(devnull, 0);
        if (devnull != 0)
            ::close(devnull);
    }
}

} // namespace

int run(Bot& bot)
{
    int in_fd = 0, out_fd = 1, status = 0;
    std::size_t debug_sent = 0;
    bool warned_bad = false, warned_step = false, warned_match = false;
    std::string line, error;
    Message msg;

    std::signal(SIGPIPE, SIG_IGN); // a closed pipe is an error from write, not a signal
    private_stdio(in_fd, out_fd);
    LineReader reader(in_fd);

    try {
        for (;;) {
            LineReader::Result got = reader.next(line);
            if (got == LineReader::Result::End)
                break; // the server closed our stdin
            if (got == LineReader::Result::TooLong) {
                log_line("ignored a line longer than 64 KiB", line);
                continue;
            }
            while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t'))
                line.pop_back();
            if (line.empty())
                continue;
            if (!parse_message(line, msg, &error)) {
                log_line("cannot read a message (" + error + ")", line);
                status = 1;
                break;
            }
            if (msg.type == Message::Type::Start) {
                bot.start(msg.start);
            } else if (msg.type == Message::Type::Sense) {
                Answer a = bot.next_move(msg.sensors, msg.run, msg.step);
                const std::string& debug = a.debug;
                bool send_debug = false;
                if (!debug.empty()) {
                    std::string problem;
                    if (debug.size() > kDebugMax) {
                        if (!warned_step)
                            std::cerr << "mazebot: step " << msg.step << ": debug object of "
                                      << debug.size() << " bytes, over " << kDebugMax
                                      << ": not sent" << std::endl;
                        warned_step = true;
                    } else if (!(problem = debug_problem(debug)).empty()) {
                        if (!warned_bad)
                            std::cerr << "mazebot: step " << msg.step << ": debug object not sent ("
                                      << problem << ")" << std::endl;
                        warned_bad = true;
                    } else if (debug_sent + debug.size() > kDebugMatchMax) {
                        if (!warned_match)
                            std::cerr << "mazebot: step " << msg.step
                                      << ": the match's debug objects reached " << kDebugMatchMax
                                      << " bytes: no more are sent" << std::endl;
                        warned_match = true;
                    } else {
                        debug_sent += debug.size();
                        send_debug = true;
                    }
                }
                std::string out;
                if (a.reset)
                    out = "{\"reset\":true";
                else
                    out = "{\"rotation\":" + std::to_string(a.rotation) +
                          ",\"movement\":" + std::to_string(a.movement);
                if (send_debug) {
                    out += ",\"debug\":";
                    out += debug;
                }
                out += "}\n";
                if (!write_all(out_fd, out))
                    break; // the server stopped listening: nothing left to do
            } else if (msg.type == Message::Type::End) {
                bot.end(msg.end);
                break;
            }
            // other message types: ignored (room for later protocol versions)
        }
    } catch (const std::exception& e) {
        std::cerr << "mazebot: the bot threw an exception: " << e.what() << std::endl;
        status = 1;
    } catch (...) {
        std::cerr << "mazebot: the bot threw an exception" << std::endl;
        status = 1;
    }
    std::cout.flush();
    std::fflush(stdout);
    if (in_fd != 0)
        ::close(in_fd);
    if (out_fd != 1)
        ::close(out_fd);
    return status;
}

} // namespace mazebot
