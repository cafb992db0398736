package main

import (
	"encoding/json"
	"math/rand"
	"testing"

	"mazebot/mazebot"
	"mazebot/mazemap"
)

// maze is a test maze: open[cell*4+d] says whether side d of the cell is open.
type maze struct {
	n    int
	open []bool
}

func (mz *maze) isOpen(x, y, d int) bool {
	return mz.open[(x*mz.n+y)*4+d]
}

func (mz *maze) setOpen(x, y, d int) {
	mz.open[(x*mz.n+y)*4+d] = true
	mz.open[((x+mazemap.DX[d])*mz.n+y+mazemap.DY[d])*4+(d+2)%4] = true
}

// generate makes a random perfect maze (depth-first), then opens a few more
// walls (loops), never on the perimeter.
func generate(n int, seed int64, loops int) *maze {
	rng := rand.New(rand.NewSource(seed))
	mz := &maze{n: n, open: make([]bool, n*n*4)}
	inside := func(x, y int) bool { return x >= 0 && y >= 0 && x < n && y < n }
	seen := make([]bool, n*n)
	stack := [][2]int{{0, 0}}
	seen[0] = true
	for len(stack) > 0 {
		c := stack[len(stack)-1]
		var dirs []int
		for d := 0; d < 4; d++ {
			if x, y := c[0]+mazemap.DX[d], c[1]+mazemap.DY[d]; inside(x, y) && !seen[x*n+y] {
				dirs = append(dirs, d)
			}
		}
		if len(dirs) == 0 {
			stack = stack[:len(stack)-1]
			continue
		}
		d := dirs[rng.Intn(len(dirs))]
		x, y := c[0]+mazemap.DX[d], c[1]+mazemap.DY[d]
		mz.setOpen(c[0], c[1], d)
		seen[x*n+y] = true
		stack = append(stack, [2]int{x, y})
	}
	for i := 0; i < loops; i++ {
		x, y, d := rng.Intn(n), rng.Intn(n), rng.Intn(4)
		if inside(x+mazemap.DX[d], y+mazemap.DY[d]) {
			mz.setOpen(x, y, d)
		}
	}
	return mz
}

// play referees one match of b on mz, as the server does, and fails the test
// if the bot runs into a wall or sends a debug object the server would drop.
func play(t *testing.T, mz *maze, b *bot) (status string, run0, run1 int) {
	t.Helper()
	inGoal := func(x, y int) bool { lo := mz.n/2 - 1; return x >= lo && x <= lo+1 && y >= lo && y <= lo+1 }
	b.Start(mazebot.StartInfo{Protocol: 1, MazeDim: mz.n, MaxSteps: 1000, MoveTimeoutMs: 1000})
	p, run, entered := mazemap.Home, 0, false
	for step := 1; step <= 1000; step++ {
		var sensors [3]int
		for i := 0; i < 3; i++ {
			d := (p.Heading + i + 3) & 3
			for x, y := p.X, p.Y; mz.isOpen(x, y, d); x, y = x+mazemap.DX[d], y+mazemap.DY[d] {
				sensors[i]++
			}
		}
		a := b.NextMove(sensors, run, step)
		if a.Debug != nil {
			if !json.Valid(a.Debug) || len(a.Debug) > mazebot.DebugMax {
				t.Fatalf("step %d: bad debug object %.200s", step, a.Debug)
			}
		}
		if a.Reset {
			if run != 0 || !entered {
				t.Fatalf("step %d: reset not allowed", step)
			}
			run, run0, p = 1, step, mazemap.Home
			continue
		}
		if a.Rotation != 0 && a.Rotation != 90 && a.Rotation != -90 || a.Movement < -3 || a.Movement > 3 {
			t.Fatalf("step %d: answer %+v", step, a)
		}
		want := p
		want.Apply(a)
		p.Apply(mazebot.Move(a.Rotation, 0))
		d, cells := p.Heading, a.Movement
		if cells < 0 {
			d, cells = (d+2)&3, -cells
		}
		for k := 0; k < cells && mz.isOpen(p.X, p.Y, d); k++ {
			p.X, p.Y = p.X+mazemap.DX[d], p.Y+mazemap.DY[d]
		}
		if p != want {
			t.Fatalf("step %d: ran into a wall: at %+v, meant %+v", step, p, want)
		}
		if inGoal(p.X, p.Y) {
			if run == 1 {
				return "finished", run0, step - run0
			}
			entered = true
		}
	}
	return "step_limit", run0, 0
}

func TestFinishesGeneratedMazes(t *testing.T) {
	for _, n := range []int{2, 4, 12, 14, 16} {
		for seed := int64(1); seed <= 5; seed++ {
			mz := generate(n, seed, n*int(seed))
			status, run0, run1 := play(t, mz, &bot{})
			if status != "finished" || run1 > run0 {
				t.Errorf("%dx%d seed %d: %s, %d + %d steps", n, n, seed, status, run0, run1)
			}
		}
	}
}

func TestWalledOffGoal(t *testing.T) {
	mz := generate(12, 3, 20)
	for x := 0; x < 12; x++ { // close the goal room
		for y := 0; y < 12; y++ {
			for d := 0; d < 4; d++ {
				inGoal := func(x, y int) bool { return x >= 5 && x <= 6 && y >= 5 && y <= 6 }
				if inGoal(x, y) != inGoal(x+mazemap.DX[d], y+mazemap.DY[d]) {
					mz.open[(x*12+y)*4+d] = false
				}
			}
		}
	}
	if status, _, _ := play(t, mz, &bot{}); status != "step_limit" {
		t.Fatal(status)
	}
}
