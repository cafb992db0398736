package mazemap

import (
	"testing"

	"mazebot/mazebot"
)

func TestNewPerimeterAndGoal(t *testing.T) {
	m := New(4)
	for i := 0; i < 4; i++ {
		if m.Edge(i, 0, Down) != Wall || m.Edge(i, 3, Up) != Wall || m.Edge(0, i, Left) != Wall || m.Edge(3, i, Right) != Wall {
			t.Fatalf("perimeter not walled at %d", i)
		}
	}
	if m.Edge(1, 1, Up) != Unknown || m.Edge(1, 2, Down) != Unknown {
		t.Fatal("inner edge not unknown")
	}
	goal := 0
	for x := 0; x < 4; x++ {
		for y := 0; y < 4; y++ {
			if m.InGoal(x, y) {
				goal++
				if x < 1 || x > 2 || y < 1 || y > 2 {
					t.Fatalf("(%d, %d) in the goal", x, y)
				}
			}
		}
	}
	if goal != 4 || m.GoalLo() != 1 {
		t.Fatal(goal, m.GoalLo())
	}
}

func TestSense(t *testing.T) {
	m := New(4)
	m.Sense(Home, [3]int{0, 2, 1}) // at (0, 0) facing up
	for y := 0; y < 2; y++ {
		if m.Edge(0, y, Up) != Open || m.Edge(0, y+1, Down) != Open {
			t.Fatalf("edge above (0, %d) not open", y)
		}
	}
	if m.Edge(0, 2, Up) != Wall || m.Edge(0, 3, Down) != Wall {
		t.Fatal("no wall after the front ray")
	}
	if m.Edge(0, 0, Right) != Open || m.Edge(1, 0, Right) != Wall || m.Edge(2, 0, Left) != Wall {
		t.Fatal("right ray")
	}
	// A reading past the border records no wall beyond it, and keeps the perimeter.
	m.Sense(Pose{3, 3, Right}, [3]int{-1, 5, 9})
	if m.Edge(3, 3, Right) != Wall || m.Edge(3, 3, Up) != Wall {
		t.Fatal("border")
	}
	for y := 0; y < 3; y++ {
		if m.Edge(3, y, Up) != Open {
			t.Fatalf("right ray down the side: (3, %d)", y)
		}
	}
}

func TestApply(t *testing.T) {
	p := Home
	for _, c := range []struct {
		a    mazebot.Answer
		want Pose
	}{
		{mazebot.Move(0, 3), Pose{0, 3, Up}},
		{mazebot.Move(90, 2), Pose{2, 3, Right}},
		{mazebot.Move(-90, -1), Pose{2, 2, Up}},
		{mazebot.Reset(), Pose{2, 2, Up}},
		{mazebot.Move(180, 0), Pose{2, 2, Up}},     // not a rotation
		{mazebot.Move(90, -7), Pose{-1, 2, Right}}, // cut to 3 cells
	} {
		p.Apply(c.a)
		if p != c.want {
			t.Fatalf("after %+v: %+v, want %+v", c.a, p, c.want)
		}
	}
}
