// mazemap.hpp: maze bookkeeping for C++ bots (header only, C++17 standard
// library): a wall map of an n x n maze and the robot's pose, as the bot's
// sensors and moves reveal them. The C++ twin of bots/c/mazemap.h.
//
//   - cells are (x, y) with (0, 0) the start corner, x to the right, y up; the
//     cell index is x * n + y (WallMap::cell);
//   - directions are absolute: UP (+y), RIGHT (+x), DOWN, LEFT, in clockwise
//     order, so (d + 1) & 3 turns right, (d + 3) & 3 left and (d + 2) & 3 is
//     the opposite side; DX / DY step one cell; the numbers are those of
//     mazebot::Side, so static_cast<mazebot::Side>(d) names a wall side;
//   - every side of every cell is Edge::Unknown, Open or Wall, stored for both
//     cells that share it; the outer perimeter starts as wall;
//   - the goal room is the 2 x 2 block of cells goal_lo() .. goal_lo() + 1 in x
//     and y (n / 2 - 1 .. n / 2), tested by in_goal.
//
// Strategies (flood fill, route planning) stay in the bots; this file only
// holds what each of them needs the same way.
#ifndef MAZEMAP_HPP
#define MAZEMAP_HPP

#include "mazebot.hpp"

#include <array>
#include <cstdlib>
#include <vector>

namespace mazemap {

enum Direction : int { UP = 0, RIGHT = 1, DOWN = 2, LEFT = 3 }; // absolute, clockwise

constexpr std::array<int, 4> DX = {0, 1, 0, -1}; // x step of each direction
constexpr std::array<int, 4> DY = {1, 0, -1, 0}; // y step of each direction

enum class Edge : unsigned char { Unknown = 0, Open = 1, Wall = 2 }; // what is known of an edge

// Where the robot is: its cell and the absolute direction it faces.
struct Pose {
    int x = 0, y = 0;
    int heading = UP;

    // Dead reckoning: the pose after answer a (rotation first, then movement
    // cells, negative = backward). A reset leaves the pose unchanged. Exact as
    // long as the bot only moves across edges it knows to be open.
    void apply(const mazebot::Answer& a)
    {
        if (a.reset)
            return;
        heading = (heading + a.rotation / 90 + 4) & 3;
        int d = a.movement >= 0 ? heading : (heading + 2) & 3;
        x += DX[d] * std::abs(a.movement);
        y += DY[d] * std::abs(a.movement);
    }
};

// The wall map. n() == 0 means no map (never initialised).
class WallMap {
public:
    WallMap() = default;

    // An all-unknown map of side n (n >= 1) with the perimeter set to wall.
    explicit WallMap(int n) : n_(n > 0 ? n : 0), edges_(static_cast<std::size_t>(n_) * n_ * 4, Edge::Unknown)
    {
        for (int i = 0; i < n_; i++) {
            set_edge(i, 0, DOWN, Edge::Wall);
            set_edge(i, n_ - 1, UP, Edge::Wall);
            set_edge(0, i, LEFT, Edge::Wall);
            set_edge(n_ - 1, i, RIGHT, Edge::Wall);
        }
    }

    int n() const { return n_; }

    // True if (x, y) is a cell of the maze.
    bool inside(int x, int y) const { return x >= 0 && y >= 0 && x < n_ && y < n_; }

    // The index of cell (x, y): x * n + y.
    int cell(int x, int y) const { return x * n_ + y; }

    // What is known of side d of cell (x, y).
    Edge edge(int x, int y, int d) const { return edges_[index(x, y, d)]; }

    // Sets side d of cell (x, y), and the same side seen from the neighbour
    // beyond it if that is inside the maze, to state.
    void set_edge(int x, int y, int d, Edge state)
    {
        int nx = x + DX[d], ny = y + DY[d];
        edges_[index(x, y, d)] = state;
        if (inside(nx, ny))
            edges_[index(nx, ny, (d + 2) & 3)] = state;
    }

    // The smallest x (and y) of the goal room: n / 2 - 1.
    int goal_lo() const { return n_ / 2 - 1; }

    // True if (x, y) is one of the four goal-room cells.
    bool in_goal(int x, int y) const
    {
        int lo = goal_lo(), hi = lo + 1;
        return x >= lo && x <= hi && y >= lo && y <= hi;
    }

    // Records one sensor reading taken at pose p: sensors = {left, front,
    // right}, each the number of open cells to the nearest wall. Along each ray
    // the first sensors[i] edges become open (stopping at the maze border), and
    // the next one a wall; a negative reading records nothing.
    void sense(const Pose& p, const mazebot::Sensors& sensors)
    {
        for (int i = 0; i < 3; i++) {
            int d = (p.heading + i + 3) & 3; // left, front, right
            int reading = sensors[i];
            int x = p.x, y = p.y;
            for (int k = 0; k < reading && inside(x + DX[d], y + DY[d]); k++) {
                set_edge(x, y, d, Edge::Open);
                x += DX[d];
                y += DY[d];
            }
            if (reading >= 0)
                set_edge(x, y, d, Edge::Wall);
        }
    }

private:
    std::size_t index(int x, int y, int d) const
    {
        return static_cast<std::size_t>(cell(x, y)) * 4 + static_cast<std::size_t>(d);
    }

    int n_ = 0;
    std::vector<Edge> edges_;
};

} // namespace mazemap

#endif // MAZEMAP_HPP
