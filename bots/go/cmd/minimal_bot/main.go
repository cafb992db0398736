// Command minimal_bot is a small, deterministic reference bot for mazearena, in
// Go: the Go twin of bots/c/minimal_bot.c (and of bots/python/simple_bot.py).
// The protocol is in package mazebot, the wall map and dead reckoning in
// package mazemap.
//
// # Strategy
//
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
// Debug drawing: each answer carries a mazebot.Debug for the replay viewer (the
// flood-fill distances as a grid, the way down them to the goal as a path, a
// line of text, and the walls it knows whenever it learnt a new one). It
// changes nothing in the moves.
package main

import (
	"fmt"
	"os"

	"mazebot/mazebot"
	"mazebot/mazemap"
)

const (
	inf    = 0x3fffffff
	maxDim = 1024 // larger mazes: the bot only turns on the spot
)

type bot struct {
	m           *mazemap.Map // walls; nil: unusable maze, only safe moves
	dist        []int        // flood fill, dist[x*n+y]
	queue       []int        // BFS queue: n*n*4 entries
	parent      []int        // run-1 BFS: parent state, -1 for the start, -2 unvisited
	act         [][2]int     // run-1 BFS: (rotation index, movement) that led to the state
	pose        mazemap.Pose // where the robot is (dead reckoning)
	run         int
	enteredGoal bool
	flooded     bool // dist holds this step's flood fill (run 0)
	wallsDrawn  int  // walls in the last debug drawing that listed them
	debug       mazebot.Debug
}

// --- run 0: flood fill, unknown = open ---------------------------------------

func (b *bot) flood() {
	m := b.m
	for i := range b.dist {
		b.dist[i] = inf
	}
	q := b.queue[:0]
	lo := m.GoalLo()
	for gx := lo; gx <= lo+1; gx++ {
		for gy := lo; gy <= lo+1; gy++ {
			if m.Inside(gx, gy) {
				b.dist[m.Cell(gx, gy)] = 0
				q = append(q, m.Cell(gx, gy))
			}
		}
	}
	for head := 0; head < len(q); head++ {
		c := q[head]
		x, y := c/m.N, c%m.N
		for d := 0; d < 4; d++ {
			nx, ny := x+mazemap.DX[d], y+mazemap.DY[d]
			if m.Edge(x, y, d) == mazemap.Wall || !m.Inside(nx, ny) {
				continue
			}
			if b.dist[m.Cell(nx, ny)] == inf {
				b.dist[m.Cell(nx, ny)] = b.dist[c] + 1
				q = append(q, m.Cell(nx, ny))
			}
		}
	}
}

func (b *bot) exploreMove() mazebot.Answer {
	m, p := b.m, b.pose
	b.flood()
	b.flooded = true
	here := b.dist[m.Cell(p.X, p.Y)]
	if here == inf {
		return mazebot.Move(90, 0) // the goal is walled off: turn on the spot
	}
	rel, d := -1, 0
	for _, o := range [4]int{0, 3, 1, 2} { // straight, left, right, back
		dd := (p.Heading + o) & 3
		nx, ny := p.X+mazemap.DX[dd], p.Y+mazemap.DY[dd]
		if m.Edge(p.X, p.Y, dd) != mazemap.Wall && m.Inside(nx, ny) && b.dist[m.Cell(nx, ny)] == here-1 {
			rel, d = o, dd
			break
		}
	}
	if rel < 0 { // in the goal room without having entered it (n = 2): step out
		for dd := 0; dd < 4 && rel < 0; dd++ {
			if m.Edge(p.X, p.Y, dd) == mazemap.Open {
				rel, d = (dd-p.Heading+4)&3, dd
			}
		}
		if rel < 0 {
			return mazebot.Move(90, 0) // look around
		}
	}
	if m.Edge(p.X, p.Y, d) != mazemap.Open {
		return mazebot.Move(90, 0) // the edge behind is unsensed: turn to look at it
	}

	rotation, sign := 0, 1
	switch rel {
	case 1:
		rotation = 90
	case 3:
		rotation = -90
	case 2:
		sign = -1
	}
	cells, x, y := 0, p.X, p.Y
	for cells < 3 && m.Edge(x, y, d) == mazemap.Open {
		nx, ny := x+mazemap.DX[d], y+mazemap.DY[d]
		if cells > 0 && b.dist[m.Cell(nx, ny)] != b.dist[m.Cell(x, y)]-1 {
			break
		}
		x, y = nx, ny
		cells++
		if m.InGoal(x, y) {
			break
		}
	}
	return mazebot.Move(rotation, sign*cells)
}

// --- run 1: BFS over (cell, heading), unknown = wall -------------------------

var (
	rotations = [3]int{0, -90, 90}
	movements = [7]int{3, 2, 1, -1, -2, -3, 0}
)

// planMove returns the first move of a shortest plan to the goal room over
// known-open edges, or false when there is none.
func (b *bot) planMove() (mazebot.Answer, bool) {
	m, p := b.m, b.pose
	start := m.Cell(p.X, p.Y)*4 + p.Heading
	for i := range b.parent {
		b.parent[i] = -2 // unvisited
	}
	b.parent[start] = -1
	q := append(b.queue[:0], start)
	for head := 0; head < len(q); head++ {
		s := q[head]
		x0, y0, h0 := s/4/m.N, s/4%m.N, s%4
		for r, rot := range rotations {
			h := (h0 + rot/90 + 4) & 3
			for _, mv := range movements {
				d, steps := h, mv
				if mv < 0 {
					d, steps = (h+2)&3, -mv
				}
				x, y, ok := x0, y0, true
				for k := 0; k < steps; k++ {
					if m.Edge(x, y, d) != mazemap.Open || !m.Inside(x+mazemap.DX[d], y+mazemap.DY[d]) {
						ok = false
						break
					}
					x += mazemap.DX[d]
					y += mazemap.DY[d]
				}
				t := m.Cell(x, y)*4 + h
				if !ok || b.parent[t] != -2 {
					continue
				}
				b.parent[t] = s
				b.act[t] = [2]int{r, mv}
				if m.InGoal(x, y) { // walk back to the first action of the plan
					for b.parent[t] != start {
						t = b.parent[t]
					}
					return mazebot.Move(rotations[b.act[t][0]], b.act[t][1]), true
				}
				q = append(q, t)
			}
		}
	}
	return mazebot.Answer{}, false
}

// --- debug drawing (the replay viewer's layer; no effect on the moves) -------

// draw builds b.debug for this step: text, the walls if they changed, and in
// run 0 the flood fill as a grid and the way down it from the robot's cell.
func (b *bot) draw(text string) {
	m, d := b.m, &b.debug
	n := m.N
	d.Clear()
	d.Text(text)
	walls := 0
	for x := 0; x < n; x++ {
		for y := 0; y < n; y++ {
			if y+1 < n && m.Edge(x, y, mazemap.Up) == mazemap.Wall {
				walls++
			}
			if x+1 < n && m.Edge(x, y, mazemap.Right) == mazemap.Wall {
				walls++
			}
		}
	}
	if walls != b.wallsDrawn { // fields are sticky: send the walls when they change
		b.wallsDrawn = walls
		d.Empty(mazebot.FieldWalls) // the field, even with no wall yet
		for x := 0; x < n; x++ {
			for y := 0; y < n; y++ {
				if y+1 < n && m.Edge(x, y, mazemap.Up) == mazemap.Wall {
					d.Wall(x, y, mazebot.Up)
				}
				if x+1 < n && m.Edge(x, y, mazemap.Right) == mazemap.Wall {
					d.Wall(x, y, mazebot.Right)
				}
			}
		}
	}
	if !b.flooded {
		return
	}
	d.Grid(n, b.dist, inf)
	var path [][2]int
	x, y := b.pose.X, b.pose.Y
	for len(path) < n*n && b.dist[m.Cell(x, y)] != inf {
		here, next := b.dist[m.Cell(x, y)], -1
		path = append(path, [2]int{x, y})
		for dd := 0; dd < 4 && here > 0 && next < 0; dd++ {
			nx, ny := x+mazemap.DX[dd], y+mazemap.DY[dd]
			if m.Edge(x, y, dd) != mazemap.Wall && m.Inside(nx, ny) && b.dist[m.Cell(nx, ny)] == here-1 {
				next = dd
			}
		}
		if next < 0 {
			break
		}
		x += mazemap.DX[next]
		y += mazemap.DY[next]
	}
	d.Path(path)
}

// --- the mazebot.Bot interface -------------------------------------------------

func (b *bot) Start(info mazebot.StartInfo) {
	n := info.MazeDim
	*b = bot{wallsDrawn: -1, pose: mazemap.Home} // the first drawing lists the walls, even none
	if n < 2 || n > maxDim {
		fmt.Fprintf(os.Stderr, "minimal_bot: cannot map a %dx%d maze; turning on the spot\n", n, n)
		return
	}
	b.m = mazemap.New(n)
	b.dist = make([]int, n*n)
	b.queue = make([]int, 0, n*n*4)
	b.parent = make([]int, n*n*4)
	b.act = make([][2]int, n*n*4)
}

func (b *bot) NextMove(sensors [3]int, run, step int) mazebot.Answer {
	if b.m == nil {
		return mazebot.Move(90, 0)
	}
	if run != b.run { // the reset was accepted: back at the start
		b.run = run
		b.pose = mazemap.Home
	}
	b.m.Sense(b.pose, sensors)
	b.flooded = false
	if run == 0 && b.enteredGoal {
		b.draw("goal room entered: reset")
		b.debug.Empty(mazebot.FieldGrid) // clear the run-0 drawing
		b.debug.Empty(mazebot.FieldPath)
		return mazebot.Reset().WithDebug(&b.debug)
	}
	a, ok := mazebot.Answer{}, false
	if run == 1 {
		a, ok = b.planMove()
	}
	if !ok {
		a = b.exploreMove()
	}
	if run == 1 {
		b.draw("run 1: shortest known path")
	} else {
		b.draw("run 0: flood fill, unknown = open")
	}
	b.pose.Apply(a) // exact: moves only cross edges known to be open
	if run == 0 && b.m.InGoal(b.pose.X, b.pose.Y) {
		b.enteredGoal = true
	}
	return a.WithDebug(&b.debug)
}

func (b *bot) End(info mazebot.EndInfo) {
	fmt.Fprintf(os.Stderr, "minimal_bot: %s", info.Status)
	if info.Score != nil {
		fmt.Fprintf(os.Stderr, ", score %.3f", *info.Score)
	}
	fmt.Fprintln(os.Stderr)
}

func main() {
	if err := mazebot.Run(&bot{}); err != nil {
		os.Exit(1)
	}
}
