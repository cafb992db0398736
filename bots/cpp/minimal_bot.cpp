// minimal_bot: a small, deterministic reference bot for mazearena, in C++17.
// The C++ twin of bots/c/minimal_bot.c (same moves, same debug drawing); the
// protocol is in mazebot.cpp, the wall map and dead reckoning in mazemap.hpp.
//
// Strategy
// --------
// Wall map. Every edge between two cells is unknown, open or wall (the outer
// perimeter starts as wall). A sensor reading d in a direction reveals the
// edges along that ray: d open edges, then a wall.
//
// Run 0 (exploration). Flood fill from the goal room over every edge not known
// to be a wall (unknown counts as open), so each cell gets an optimistic
// distance to the goal. Each step the bot heads to a neighbour one closer,
// preferring straight ahead, then left, right, back, and moves up to 3 cells
// while the cells keep getting closer and the edges are known open (so it
// never hits a wall and always knows where it is). It re-plans every step.
// After a step that ended in the goal room it answers reset.
//
// Run 1 (timed run). Breadth-first search over (cell, heading) using only
// edges known to be open (unknown = wall): one step is one rotation (-90, 0,
// 90) followed by a straight move of -3..3 cells, exactly the game's move.
// The bot follows the shortest such plan, re-planned every step.
//
// If the goal cannot be reached (the map proves it walled off), the bot turns
// on the spot until the step limit: it never crashes and never hits a wall.
//
// Debug drawing: each answer carries a mazebot::Debug for the replay viewer
// (the flood-fill distances as a grid, the way down them to the goal as a
// path, a line of text, and the walls it knows whenever it learnt a new one).
// It changes nothing in the moves.
#include "mazebot.hpp"
#include "mazemap.hpp"

#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <utility>
#include <vector>

namespace {

using mazebot::Answer;
using mazemap::DX;
using mazemap::DY;
using mazemap::Edge;

constexpr int INF = 0x3fffffff;
constexpr int MAX_DIM = 1024; // larger mazes: the bot only turns on the spot

class MinimalBot : public mazebot::Bot {
public:
    void start(const mazebot::StartInfo& info) override
    {
        int n = info.maze_dim;
        *this = MinimalBot(); // a fresh state for every match
        if (n >= 2 && n <= MAX_DIM) {
            std::size_t cells = static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
            map_ = mazemap::WallMap(n);
            dist_.assign(cells, INF);
            queue_.assign(cells * 4, 0);
            parent_.assign(cells * 4, -2);
            act_.assign(cells * 4, {0, 0});
        } else {
            std::cerr << "minimal_bot: cannot map a " << n << "x" << n
                      << " maze; turning on the spot" << std::endl;
        }
    }

    Answer next_move(const mazebot::Sensors& sensors, int run, int step) override
    {
        (void)step;
        if (map_.n() == 0)
            return mazebot::move(90, 0);
        if (run != run_) { // the reset was accepted: back at the start
            run_ = run;
            pose_ = mazemap::Pose();
        }
        map_.sense(pose_, sensors);
        flooded_ = false;
        if (run == 0 && entered_goal_) {
            draw("goal room entered: reset");
            debug_.empty(mazebot::Field::Grid); // clear the run-0 drawing
            debug_.empty(mazebot::Field::Path);
            return mazebot::reset().with_debug(debug_);
        }
        Answer a;
        if (run != 1 || !plan_move(a))
            a = explore_move();
        draw(run == 1 ? "run 1: shortest known path" : "run 0: flood fill, unknown = open");
        pose_.apply(a); // exact: moves only cross edges known to be open
        if (run == 0 && map_.in_goal(pose_.x, pose_.y))
            entered_goal_ = true;
        return a.with_debug(debug_);
    }

    void end(const mazebot::EndInfo& info) override
    {
        std::cerr << "minimal_bot: " << info.status;
        if (info.score)
            std::cerr << ", score " << std::fixed << std::setprecision(3) << *info.score;
        std::cerr << std::endl;
    }

private:
    // --- run 0: flood fill, unknown = open ---------------------------------

    void flood()
    {
        int n = map_.n(), lo = map_.goal_lo();
        std::size_t head = 0, tail = 0;
        dist_.assign(dist_.size(), INF);
        for (int gx = lo; gx <= lo + 1; gx++)
            for (int gy = lo; gy <= lo + 1; gy++) {
                if (!map_.inside(gx, gy))
                    continue;
                dist_[map_.cell(gx, gy)] = 0;
                queue_[tail++] = map_.cell(gx, gy);
            }
        while (head < tail) {
            int c = queue_[head++], x = c / n, y = c % n;
            for (int d = 0; d < 4; d++) {
                int nx = x + DX[d], ny = y + DY[d];
                if (map_.edge(x, y, d) == Edge::Wall || !map_.inside(nx, ny))
                    continue;
                if (dist_[map_.cell(nx, ny)] == INF) {
                    dist_[map_.cell(nx, ny)] = dist_[c] + 1;
                    queue_[tail++] = map_.cell(nx, ny);
                }
            }
        }
    }

    int dist_at(int x, int y) const { return dist_[map_.cell(x, y)]; }

    Answer explore_move()
    {
        static const int order[4] = {0, 3, 1, 2}; // straight, left, right, back
        int rel = -1, d = 0;

        flood();
        flooded_ = true;
        int here = dist_at(pose_.x, pose_.y);
        if (here == INF)
            return mazebot::move(90, 0); // the goal is walled off: turn on the spot
        for (int i = 0; i < 4; i++) {
            int dd = (pose_.heading + order[i]) & 3;
            int nx = pose_.x + DX[dd], ny = pose_.y + DY[dd];
            if (map_.edge(pose_.x, pose_.y, dd) != Edge::Wall && map_.inside(nx, ny) &&
                dist_at(nx, ny) == here - 1) {
                rel = order[i];
                d = dd;
                break;
            }
        }
        if (rel < 0) { // in the goal room without having entered it (n = 2): step out
            for (int dd = 0; dd < 4 && rel < 0; dd++)
                if (map_.edge(pose_.x, pose_.y, dd) == Edge::Open) {
                    rel = (dd - pose_.heading + 4) & 3;
                    d = dd;
                }
            if (rel < 0)
                return mazebot::move(90, 0); // look around
        }
        if (map_.edge(pose_.x, pose_.y, d) != Edge::Open)
            return mazebot::move(90, 0); // the edge behind is unsensed: turn to look at it

        int rotation = rel == 1 ? 90 : rel == 3 ? -90 : 0;
        int sign = rel == 2 ? -1 : 1;
        int cells = 0, x = pose_.x, y = pose_.y;
        while (cells < 3 && map_.edge(x, y, d) == Edge::Open) {
            int nx = x + DX[d], ny = y + DY[d];
            if (cells > 0 && dist_at(nx, ny) != dist_at(x, y) - 1)
                break;
            x = nx;
            y = ny;
            cells++;
            if (map_.in_goal(x, y))
                break;
        }
        return mazebot::move(rotation, sign * cells);
    }

    // --- run 1: BFS over (cell, heading), unknown = wall -----------------------

    // The first move of a shortest plan to the goal room over known-open
    // edges, in out; false when the map has none yet.
    bool plan_move(Answer& out)
    {
        static const int rotations[3] = {0, -90, 90};
        static const int movements[7] = {3, 2, 1, -1, -2, -3, 0};
        int n = map_.n();
        std::size_t head = 0, tail = 0;
        int start = map_.cell(pose_.x, pose_.y) * 4 + pose_.heading;

        parent_.assign(parent_.size(), -2); // unvisited
        parent_[start] = -1;
        queue_[tail++] = start;
        while (head < tail) {
            int s = queue_[head++];
            int x0 = s / 4 / n, y0 = s / 4 % n, h0 = s % 4;
            for (int r = 0; r < 3; r++) {
                int h = (h0 + rotations[r] / 90 + 4) & 3;
                for (int mv : movements) {
                    int d = mv >= 0 ? h : (h + 2) & 3;
                    int x = x0, y = y0;
                    bool ok = true;
                    for (int k = 0; k < std::abs(mv); k++) {
                        if (map_.edge(x, y, d) != Edge::Open || !map_.inside(x + DX[d], y + DY[d])) {
                            ok = false;
                            break;
                        }
                        x += DX[d];
                        y += DY[d];
                    }
                    int t = map_.cell(x, y) * 4 + h;
                    if (!ok || parent_[t] != -2)
                        continue;
                    parent_[t] = s;
                    act_[t] = {rotations[r], mv};
                    if (map_.in_goal(x, y)) { // walk back to the first action of the plan
                        while (parent_[t] != start)
                            t = parent_[t];
                        out = mazebot::move(act_[t].first, act_[t].second);
                        return true;
                    }
                    queue_[tail++] = t;
                }
            }
        }
        return false;
    }

    // --- debug drawing (the replay viewer's layer; no effect on the moves) -----

    // Builds debug_ for this step: text, the walls if they changed, and in run 0
    // the flood fill as a grid and the way down it from the robot's cell.
    void draw(const char* text)
    {
        using mazemap::RIGHT;
        using mazemap::UP;
        int n = map_.n(), walls = 0;
        debug_.clear();
        debug_.text(text);
        for (int x = 0; x < n; x++)
            for (int y = 0; y < n; y++)
                walls += (y + 1 < n && map_.edge(x, y, UP) == Edge::Wall) +
                         (x + 1 < n && map_.edge(x, y, RIGHT) == Edge::Wall);
        if (walls != walls_drawn_) { // fields are sticky: send the walls when they change
            walls_drawn_ = walls;
            debug_.empty(mazebot::Field::Walls); // the field, even with no wall yet
            for (int x = 0; x < n; x++)
                for (int y = 0; y < n; y++) {
                    if (y + 1 < n && map_.edge(x, y, UP) == Edge::Wall)
                        debug_.wall(x, y, mazebot::Side::Up);
                    if (x + 1 < n && map_.edge(x, y, RIGHT) == Edge::Wall)
                        debug_.wall(x, y, mazebot::Side::Right);
                }
        }
        if (!flooded_)
            return;
        debug_.grid(n, dist_, INF);
        std::vector<std::pair<int, int>> path;
        int x = pose_.x, y = pose_.y;
        while (static_cast<int>(path.size()) < n * n && dist_at(x, y) != INF) {
            int here = dist_at(x, y), next = -1;
            path.emplace_back(x, y);
            for (int dd = 0; dd < 4 && here > 0 && next < 0; dd++) {
                int nx = x + DX[dd], ny = y + DY[dd];
                if (map_.edge(x, y, dd) != Edge::Wall && map_.inside(nx, ny) &&
                    dist_at(nx, ny) == here - 1)
                    next = dd;
            }
            if (next < 0)
                break;
            x += DX[next];
            y += DY[next];
        }
        debug_.path(path);
    }

    mazemap::WallMap map_;                  // walls; n() = 0: unusable maze, only safe moves
    std::vector<int> dist_;                 // flood fill
    std::vector<int> queue_;                // BFS queue: n*n*4 entries
    std::vector<int> parent_;               // run-1 BFS: parent state, -1 (start) or -2
    std::vector<std::pair<int, int>> act_;  // run-1 BFS: (rotation, movement) into the state
    mazemap::Pose pose_;                    // where the robot is (dead reckoning)
    int run_ = 0;
    bool entered_goal_ = false;
    bool flooded_ = false;                  // dist_ holds this step's flood fill (run 0)
    int walls_drawn_ = -1;                  // walls in the last drawing that listed them
    mazebot::Debug debug_;                  // the debug drawing being built
};

} // namespace

int main()
{
    MinimalBot bot;
    return mazebot::run(bot);
}
