// Package mazemap is the maze bookkeeping of a mazearena bot: a wall map of an
// n x n maze and the robot's pose, as the bot's sensors and moves reveal them.
//
//   - Cells are (x, y) with (0, 0) the start corner, x to the right, y up; the
//     cell index is x*n + y (Map.Cell).
//   - Directions are absolute: Up (+y), Right (+x), Down, Left, in clockwise
//     order, so (d+1)&3 turns right, (d+3)&3 left and (d+2)&3 is the opposite
//     side; DX and DY step one cell.
//   - Every side of every cell is Unknown, Open or Wall, stored for both cells
//     that share it; the outer perimeter starts as Wall (New).
//   - The goal room is the 2 x 2 block of cells GoalLo() .. GoalLo()+1 in x and
//     y (n/2 - 1 .. n/2), tested by InGoal.
//
// Strategies (flood fill, route planning) stay in the bots; this package only
// holds what each of them needs the same way. It is the Go twin of the C kit's
// mazemap.h.
package mazemap

import "mazebot/mazebot"

// Absolute directions, clockwise (the numbers of mazebot.Up .. mazebot.Left).
const (
	Up = iota
	Right
	Down
	Left
)

// What is known of an edge.
const (
	Unknown = 0
	Open    = 1
	Wall    = 2
)

// DX and DY are the x and y steps of each direction.
var (
	DX = [4]int{0, 1, 0, -1}
	DY = [4]int{1, 0, -1, 0}
)

// Map is the wall map of an n x n maze.
type Map struct {
	N     int     // side of the maze
	edges []uint8 // edges[Cell(x, y)*4 + d]: Unknown, Open or Wall
}

// New returns an all-unknown map of side n (n >= 1) with the perimeter set to
// Wall.
func New(n int) *Map {
	m := &Map{N: n, edges: make([]uint8, n*n*4)}
	for i := 0; i < n; i++ {
		m.SetEdge(i, 0, Down, Wall)
		m.SetEdge(i, n-1, Up, Wall)
		m.SetEdge(0, i, Left, Wall)
		m.SetEdge(n-1, i, Right, Wall)
	}
	return m
}

// Inside says whether (x, y) is a cell of the maze.
func (m *Map) Inside(x, y int) bool {
	return x >= 0 && y >= 0 && x < m.N && y < m.N
}

// Cell is the index of cell (x, y): x*n + y.
func (m *Map) Cell(x, y int) int {
	return x*m.N + y
}

// Edge is what is known of side d of cell (x, y).
func (m *Map) Edge(x, y, d int) uint8 {
	return m.edges[m.Cell(x, y)*4+d]
}

// SetEdge sets side d of cell (x, y), and the same side seen from the neighbour
// beyond it if that is inside the maze, to state.
func (m *Map) SetEdge(x, y, d int, state uint8) {
	m.edges[m.Cell(x, y)*4+d] = state
	if nx, ny := x+DX[d], y+DY[d]; m.Inside(nx, ny) {
		m.edges[m.Cell(nx, ny)*4+((d+2)&3)] = state
	}
}

// GoalLo is the smallest x (and y) of the goal room: n/2 - 1.
func (m *Map) GoalLo() int {
	return m.N/2 - 1
}

// InGoal says whether (x, y) is one of the four goal-room cells.
func (m *Map) InGoal(x, y int) bool {
	lo := m.GoalLo()
	return x >= lo && x <= lo+1 && y >= lo && y <= lo+1
}

// Pose is where the robot is: its cell and the absolute direction it faces.
type Pose struct {
	X, Y, Heading int
}

// Home is the pose at the start of each run: cell (0, 0), facing up.
var Home = Pose{0, 0, Up}

// Sense records one sensor reading taken at pose p: sensors = {left, front,
// right}, each the number of open cells to the nearest wall. Along each ray the
// first sensors[i] edges become Open (stopping at the maze border), and the
// next one a Wall; a negative reading records nothing.
func (m *Map) Sense(p Pose, sensors [3]int) {
	for i := 0; i < 3; i++ {
		d := (p.Heading + i + 3) & 3 // left, front, right
		x, y := p.X, p.Y
		for k := 0; k < sensors[i] && m.Inside(x+DX[d], y+DY[d]); k++ {
			m.SetEdge(x, y, d, Open)
			x += DX[d]
			y += DY[d]
		}
		if sensors[i] >= 0 {
			m.SetEdge(x, y, d, Wall)
		}
	}
}

// Apply is dead reckoning: the pose after answer a (rotation first, then
// movement cells, negative = backward), read with the server's lenient rules (a
// rotation other than -90, 0 or 90 is none; a movement beyond 3 cells is 3). A
// reset leaves the pose unchanged. It is exact as long as the bot only moves
// across edges it knows to be open.
func (p *Pose) Apply(a mazebot.Answer) {
	if a.Reset {
		return
	}
	switch a.Rotation {
	case -90:
		p.Heading = (p.Heading + 3) & 3
	case 90:
		p.Heading = (p.Heading + 1) & 3
	}
	d, cells := p.Heading, a.Movement
	if cells < 0 {
		d, cells = (d+2)&3, -cells
	}
	if cells > 3 || cells < 0 { // < 0: -MinInt overflowed
		cells = 3
	}
	p.X += DX[d] * cells
	p.Y += DY[d] * cells
}
