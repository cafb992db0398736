// mazebot.hpp: the protocol side of a mazearena bot written in C++17.
//
// The server talks to a bot through line-delimited JSON on stdin/stdout
// (docs/PROTOCOL.md). This helper does all of it, so that a bot is a class
// with one to three virtual functions and a call to mazebot::run():
//
//     #include "mazebot.hpp"
//
//     class MyBot : public mazebot::Bot {
//     public:
//         mazebot::Answer next_move(const mazebot::Sensors& sensors, int run,
//                                   int step) override
//         {
//             if (sensors[1] > 0)
//                 return mazebot::move(0, 1);   // straight on, one cell
//             return mazebot::move(90, 0);      // turn right on the spot
//         }
//     };
//
//     int main()
//     {
//         MyBot bot;
//         return mazebot::run(bot);
//     }
//
// The callbacks (members of mazebot::Bot):
//
//   start(info)          optional; once, before the first move. info.maze_dim is
//                        the side of the maze, info.seed is there so a randomized
//                        bot can be made reproducible.
//   next_move(sensors, run, step)
//                        required; once per step. sensors = {left, front, right}:
//                        open cells to the nearest wall, relative to the heading.
//                        run is 0 (exploration) or 1 (timed run); step is the
//                        shared 1-based step counter. Return move(rotation,
//                        movement) (rotation -90, 0 or 90 degrees, clockwise
//                        positive, applied first; movement -3..3 cells, negative =
//                        backward) or reset() (ends run 0; only accepted once the
//                        robot has ended a move in the goal room during run 0).
//   end(info)            optional; once, with the server's final message.
//
// Printing is safe: while run() is active, file descriptor 1 (std::cout,
// printf, child processes) is a copy of stderr, which the server keeps as the
// bot's log; protocol lines go through a private copy of the real stdout, and
// each answer is written at once with write(2) (nothing is left in a buffer).
// fd 0 reads /dev/null, so std::cin cannot eat the server's messages by accident.
//
// Debug drawing (docs/PROTOCOL.md, "Debug drawing"): an answer may carry a
// debug object that the replay viewer draws over the maze. Build it with a
// mazebot::Debug and attach it to the answer:
//
//     mazebot::Debug d;
//     d.text("run ", run, ": ", steps, " steps to go");
//     d.wall(2, 3, mazebot::Side::Right);
//     d.grid(n, dist, INF);                     // dist[x * n + y]; INF shown as null
//     return mazebot::move(0, 1).with_debug(d);
//
// Input lines may be up to kMaxLine bytes; the JSON is read by a small
// hand-written parser that accepts any field order, any whitespace, unknown
// fields (skipped, whatever their type) and a trailing "\r". Unknown message
// types are ignored. Only the C++17 standard library and POSIX (dup, dup2,
// open, read, write) are used.
#ifndef MAZEBOT_HPP
#define MAZEBOT_HPP

#include <array>
#include <cstddef>
#include <cstdint>
#include <locale>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace mazebot {

// Longest input line accepted, not counting the "\n" (the protocol's 64 KiB).
constexpr std::size_t kMaxLine = 65536;

// The server keeps at most this many bytes of one step's debug JSON, and of a
// whole match's. run() sends nothing beyond them (one line on stderr says so).
constexpr std::size_t kDebugMax = 16 * 1024;
constexpr std::size_t kDebugMatchMax = 64 * 1024;

// {left, front, right}: open cells to the nearest wall, relative to the heading.
using Sensors = std::array<int, 3>;

// The start message.
struct StartInfo {
    int protocol = 1;             // 1
    int maze_dim = 0;             // side of the maze, e.g. 12
    int max_steps = 1000;         // shared by both runs
    std::uint64_t seed = 0;       // for reproducible randomness
    int move_timeout_ms = 1000;   // time per answer
};

// The end message. Fields the server sent as null (or not at all) are empty.
struct EndInfo {
    std::string status;                    // "finished", "step_limit", "timeout", ...
    std::optional<double> score;           // only when finished
    std::optional<long long> run0_steps;   // once a reset was accepted
    std::optional<long long> run1_steps;   // only when finished
};

class Debug;

// One answer: a move, or a reset (then rotation and movement are ignored),
// with an optional debug object (its JSON text; empty: none).
struct Answer {
    int rotation = 0;   // -90, 0 or 90
    int movement = 0;   // -3 .. 3
    bool reset = false; // true: {"reset":true}
    std::string debug;  // a JSON object sent as the answer's "debug", or empty

    // This answer with d's drawing attached: `return move(0, 1).with_debug(d);`.
    // Nothing is attached when d has no field.
    Answer with_debug(const Debug& d) const;

    // The same with a JSON object's text of your own (e.g. written by hand);
    // run() checks that it is one complete, valid JSON object in UTF-8 within
    // kDebugMax bytes and otherwise leaves it out, with a line on stderr.
    Answer with_debug_json(std::string json) const;
};

// Answers for next_move.
inline Answer move(int rotation, int movement)
{
    Answer a;
    a.rotation = rotation;
    a.movement = movement;
    return a;
}

inline Answer reset()
{
    Answer a;
    a.reset = true;
    return a;
}

// A bot: derive from it and override next_move (start and end are optional).
class Bot {
public:
    virtual ~Bot() = default;
    virtual void start(const StartInfo& info) { (void)info; }
    virtual Answer next_move(const Sensors& sensors, int run, int step) = 0;
    virtual void end(const EndInfo& info) { (void)info; }
};

// Plays one match over stdin/stdout. Returns 0 after the end message or when
// stdin closes (or the server stops reading our answers); 1 after a message it
// cannot use or an exception thrown by a callback (a diagnostic is written to
// stderr), so `return mazebot::run(bot);` from main gives the right exit status.
int run(Bot& bot);

// ------------------------------------------------------------------------
// Debug drawing.

// Wall sides, the same numbers as mazemap.hpp's UP .. LEFT.
enum class Side { Up = 0, Right = 1, Down = 2, Left = 3 };

// The fields of a debug object, for Debug::empty.
enum class Field { Text = 0, Walls, Cells, Grid, Colors, Path };

// A debug object being built: what the bot believes, drawn by the replay viewer
// at this step. (0, 0) is the bottom-left cell, x to the right, y up. Every
// field is optional and sticky in the viewer (each shows the latest one sent),
// so send big ones only when they change. The object's JSON never exceeds
// kDebugMax bytes: an item that would take it over is left out (the function
// returns false and dropped() counts it). Strings are escaped, and bytes that
// are not valid UTF-8 become U+FFFD, so json() is always valid JSON.
class Debug {
public:
    // Empties the object (call it at the start of every step).
    void clear();

    // A line of text shown with the step (replaces an earlier one; cut at
    // 4 KiB). With several arguments they are written one after the other as
    // by an ostream: d.text("run ", run, ": ", n, " steps to go").
    bool text(std::string_view s);
    template <typename A, typename B, typename... Rest>
    bool text(const A& a, const B& b, const Rest&... rest)
    {
        std::ostringstream out;
        out.imbue(std::locale::classic());
        out << a << b;
        (out << ... << rest);
        return text(std::string_view(out.str()));
    }

    // A wall the bot believes in, on side `side` of cell (x, y).
    bool wall(int x, int y, Side side);

    // A number, or a short text, written in cell (x, y).
    bool cell(int x, int y, long long value);
    bool cell(int x, int y, std::string_view text);

    // Values for the whole n x n maze: values[x * n + y] (the maze file's
    // order); a value equal to null_value is sent as null (nothing shown).
    // Replaces an earlier grid. The vector form checks values.size() >= n * n.
    bool grid(int n, const int* values, int null_value);
    bool grid(int n, const std::vector<int>& values, int null_value);

    // A cell colour, "#rgb" or "#rrggbb" (anything else: false, nothing added).
    bool color(int x, int y, std::string_view hex);

    // A planned path through the listed cells, {x, y} each (replaces an earlier
    // one; an empty list sends an empty path, which clears the drawn one).
    bool path(const std::vector<std::pair<int, int>>& cells);

    // Sends the field empty ("text": "", or an empty list): clears what the
    // viewer shows for it.
    bool empty(Field field);

    // True when at least one field is set.
    bool any() const;

    // The object's JSON, or "" when no field is set.
    std::string json() const;

    // The length of json() in bytes (at most kDebugMax), without writing it.
    std::size_t size() const;

    // Items left out since clear().
    int dropped() const { return dropped_; }

private:
    struct Slot {
        bool present = false;           // the field is sent
        std::vector<std::string> items; // list fields: every item; others: 0 or 1 value
        std::size_t bytes = 0;          // JSON bytes of the items
    };
    static constexpr int kFields = 6;

    bool add(Field field, std::string item);
    std::size_t size_with(Field f, bool present, std::size_t count, std::size_t bytes) const;

    std::array<Slot, kFields> fields_{};
    int dropped_ = 0;
};

// ------------------------------------------------------------------------
// The parser, exposed for tests.

struct Message {
    enum class Type { Other, Start, Sense, End };
    Type type = Type::Other; // Other: a message type this helper does not know
    StartInfo start;         // Start
    Sensors sensors{};       // Sense
    int run = 0;             // Sense
    int step = 0;            // Sense
    EndInfo end;             // End
};

// Parses one JSON line (without its "\n"). Returns true on success, or false
// with a short reason in *error (when not null) if the line is not a JSON
// object or a known message lacks a field it needs.
bool parse_message(std::string_view line, Message& msg, std::string* error = nullptr);

// Why `json` cannot be sent as a debug object ("not UTF-8", "not a JSON
// object", ...), or an empty string if it can (size limits not included).
std::string debug_problem(std::string_view json);

} // namespace mazebot

#endif // MAZEBOT_HPP
