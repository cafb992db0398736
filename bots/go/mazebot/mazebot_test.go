package mazebot

import (
	"bytes"
	"encoding/json"
	"errors"
	"fmt"
	"math"
	"os"
	"os/exec"
	"strings"
	"testing"
	"unicode/utf8"
)

// --- the parser ----------------------------------------------------------------

func TestParseStart(t *testing.T) {
	msg, err := ParseMessage([]byte(`{"type":"start","protocol":1,"maze_dim":12,"max_steps":1000,"seed":7,"move_timeout_ms":1000}`))
	if err != nil {
		t.Fatal(err)
	}
	want := StartInfo{Protocol: 1, MazeDim: 12, MaxSteps: 1000, Seed: 7, MoveTimeoutMs: 1000}
	if msg.Type != MsgStart || msg.Start != want {
		t.Fatalf("got %+v", msg)
	}
}

func TestParseAnyOrderWhitespaceUnknownFields(t *testing.T) {
	line := " { \"future\" : {\"a\":[1,2,{\"b\":null}],\"c\":\"}\"} ,\t\"maze_dim\" : 16 ," +
		" \"type\":\"start\", \"x\": [[]], \"y\": true, \"z\": -1.5e3 }\r"
	msg, err := ParseMessage([]byte(line))
	if err != nil {
		t.Fatal(err)
	}
	if msg.Type != MsgStart || msg.Start.MazeDim != 16 {
		t.Fatalf("got %+v", msg)
	}
	// Absent fields keep their defaults.
	if msg.Start.Protocol != 1 || msg.Start.MaxSteps != 1000 || msg.Start.MoveTimeoutMs != 1000 || msg.Start.Seed != 0 {
		t.Fatalf("defaults: got %+v", msg.Start)
	}
}

func TestParseSense(t *testing.T) {
	msg, err := ParseMessage([]byte(`{"sensors":[0,11,2],"step":34,"run":1,"type":"sense","extra":{"deep":[[[]]]}}`))
	if err != nil {
		t.Fatal(err)
	}
	if msg.Type != MsgSense || msg.Sensors != [3]int{0, 11, 2} || msg.Run != 1 || msg.Step != 34 {
		t.Fatalf("got %+v", msg)
	}
}

func TestParseEnd(t *testing.T) {
	msg, err := ParseMessage([]byte(`{"type":"end","status":"finished","score":22.133,"run0_steps":34,"run1_steps":21}`))
	if err != nil {
		t.Fatal(err)
	}
	e := msg.End
	if msg.Type != MsgEnd || e.Status != "finished" || e.Score == nil || *e.Score != 22.133 ||
		e.Run0Steps == nil || *e.Run0Steps != 34 || e.Run1Steps == nil || *e.Run1Steps != 21 {
		t.Fatalf("got %+v", msg)
	}
	msg, err = ParseMessage([]byte(`{"type":"end","status":"timeout","score":null,"run0_steps":null,"run1_steps":null}`))
	if err != nil {
		t.Fatal(err)
	}
	if e := msg.End; e.Status != "timeout" || e.Score != nil || e.Run0Steps != nil || e.Run1Steps != nil {
		t.Fatalf("nulls: got %+v", e)
	}
	msg, err = ParseMessage([]byte(`{"type":"end"}`))
	if err != nil || msg.Type != MsgEnd || msg.End.Status != "" {
		t.Fatalf("bare end: %+v %v", msg, err)
	}
}

func TestParseOtherTypes(t *testing.T) {
	for _, line := range []string{
		`{"type":"hello","maze_dim":"x"}`,
		`{"type":5}`,
		`{"no_type":true}`,
		`{}`,
		`{"type":"START","maze_dim":12}`,
	} {
		msg, err := ParseMessage([]byte(line))
		if err != nil || msg.Type != MsgOther {
			t.Errorf("%s: got %+v, %v", line, msg, err)
		}
	}
}

func TestParseErrors(t *testing.T) {
	for _, line := range []string{
		``,
		`   `,
		`null`,
		`[1,2]`,
		`"start"`,
		`{`,
		`{"type":"start","maze_dim":12`,
		`{"type":"start","maze_dim":12} x`,
		`{"type":"start","maze_dim":12}{}`,
		`{"type":"start"}`,
		`{"type":"start","maze_dim":"12"}`,
		`{"type":"start","maze_dim":null}`,
		`{"type":"sense","run":0}`,
		`{"type":"sense","sensors":[1,2,3]}`,
		`{"type":"sense","run":"0","sensors":[1,2,3]}`,
		`{"type":"sense","run":0,"sensors":[1,2]}`,
		`{"type":"sense","run":0,"sensors":[1,2,3,4]}`,
		`{"type":"sense","run":0,"sensors":{"0":1}}`,
		`{'type':'end'}`,
	} {
		if msg, err := ParseMessage([]byte(line)); err == nil {
			t.Errorf("%q: no error, got %+v", line, msg)
		}
	}
}

func TestParseNumbers(t *testing.T) {
	cases := []struct {
		line string
		seed uint64
		dim  int
	}{
		{`{"type":"start","maze_dim":12,"seed":18446744073709551615}`, math.MaxUint64, 12},
		{`{"type":"start","maze_dim":12,"seed":99999999999999999999999}`, math.MaxUint64, 12},
		{`{"type":"start","maze_dim":12,"seed":9223372036854775808}`, 1 << 63, 12},
		{`{"type":"start","maze_dim":12,"seed":-1}`, math.MaxUint64, 12},
		{`{"type":"start","maze_dim":12.9,"seed":7.0}`, 7, 12},
		{`{"type":"start","maze_dim":1e1}`, 0, 10},
		{`{"type":"start","maze_dim":-0}`, 0, 0},
		{`{"type":"start","maze_dim":1e999}`, 0, math.MaxInt},
		{`{"type":"start","maze_dim":-99999999999999999999999}`, 0, math.MinInt},
	}
	for _, c := range cases {
		msg, err := ParseMessage([]byte(c.line))
		if err != nil {
			t.Errorf("%s: %v", c.line, err)
			continue
		}
		if msg.Start.Seed != c.seed || msg.Start.MazeDim != c.dim {
			t.Errorf("%s: seed %d dim %d, want %d %d", c.line, msg.Start.Seed, msg.Start.MazeDim, c.seed, c.dim)
		}
	}
	msg, err := ParseMessage([]byte(`{"type":"sense","run":0,"step":3,"sensors":[1.9,null,"x"]}`))
	if err != nil || msg.Sensors != [3]int{1, 0, 0} {
		t.Fatalf("sensors: %+v %v", msg, err)
	}
}

// --- the conversation ---------------------------------------------------------------

// scripted answers from a list and records what it was told.
type scripted struct {
	answers []Answer
	starts  []StartInfo
	senses  []string
	ends    []EndInfo
}

func (s *scripted) Start(info StartInfo) { s.starts = append(s.starts, info) }

func (s *scripted) NextMove(sensors [3]int, run, step int) Answer {
	s.senses = append(s.senses, fmt.Sprint(sensors, run, step))
	a := s.answers[0]
	s.answers = s.answers[1:]
	return a
}

func (s *scripted) End(info EndInfo) { s.ends = append(s.ends, info) }

// serve plays input to bot and returns its answers; the package's log lines
// go to *logged when it is not nil.
func serve(t *testing.T, bot Bot, input string, logged ...*string) (string, error) {
	t.Helper()
	var out, log bytes.Buffer
	logOutput = &log
	defer func() { logOutput = os.Stderr }()
	err := Serve(bot, strings.NewReader(input), &out)
	for _, l := range logged {
		*l = log.String()
	}
	return out.String(), err
}

func TestServeExchange(t *testing.T) {
	bot := &scripted{answers: []Answer{Move(0, 3), Move(-90, -2), Reset(), Move(90, 1)}}
	input := `{"type":"start","protocol":1,"maze_dim":12,"max_steps":1000,"seed":7,"move_timeout_ms":1000}` + "\r\n" +
		"\n" +
		`{"type":"sense","run":0,"step":1,"sensors":[0,11,0]}` + "\n" +
		`{"type":"news","text":"ignored"}` + "\n" +
		`{"type":"sense","run":0,"step":2,"sensors":[0,8,0]}` + " \t\r\n" +
		`{"type":"sense","run":0,"step":3,"sensors":[1,1,0]}` + "\n" +
		`{"type":"sense","run":1,"step":4,"sensors":[0,11,0]}` + "\n" +
		`{"type":"end","status":"finished","score":1.133,"run0_steps":3,"run1_steps":1}` + "\n" +
		`{"type":"sense","run":1,"step":5,"sensors":[0,11,0]}` + "\n"
	out, err := serve(t, bot, input)
	if err != nil {
		t.Fatal(err)
	}
	want := `{"rotation":0,"movement":3}` + "\n" + `{"rotation":-90,"movement":-2}` + "\n" +
		`{"reset":true}` + "\n" + `{"rotation":90,"movement":1}` + "\n"
	if out != want {
		t.Fatalf("answers:\n%s\nwant:\n%s", out, want)
	}
	if len(bot.starts) != 1 || bot.starts[0].MazeDim != 12 || bot.starts[0].Seed != 7 {
		t.Fatalf("starts: %+v", bot.starts)
	}
	if got := strings.Join(bot.senses, "|"); got != "[0 11 0] 0 1|[0 8 0] 0 2|[1 1 0] 0 3|[0 11 0] 1 4" {
		t.Fatalf("senses: %s", got)
	}
	if len(bot.ends) != 1 || *bot.ends[0].Score != 1.133 {
		t.Fatalf("ends: %+v", bot.ends)
	}
}

func TestServeEOFAndLastLineWithoutNewline(t *testing.T) {
	bot := &scripted{answers: []Answer{Move(0, 1)}}
	out, err := serve(t, bot, `{"type":"sense","run":0,"step":1,"sensors":[0,1,0]}`)
	if err != nil || out != `{"rotation":0,"movement":1}`+"\n" {
		t.Fatalf("%q %v", out, err)
	}
	if out, err := serve(t, &scripted{}, ""); err != nil || out != "" {
		t.Fatalf("empty input: %q %v", out, err)
	}
}

func TestServeLongLines(t *testing.T) {
	bot := &scripted{answers: []Answer{Move(0, 1), Move(0, 2)}}
	long := `{"type":"sense","run":0,"step":1,"sensors":[0,1,0],"pad":"` + strings.Repeat("x", 3*MaxLine) + `"}`
	fits := `{"type":"sense","run":0,"step":2,"sensors":[0,1,0],"pad":"`
	fits += strings.Repeat("y", MaxLine-len(fits)-2) + `"}`
	if len(fits) != MaxLine {
		t.Fatal(len(fits))
	}
	var log string
	out, err := serve(t, bot, long+"\n"+fits+"\n"+`{"type":"sense","run":0,"step":3,"sensors":[0,1,0]}`+"\n", &log)
	if err != nil {
		t.Fatal(err)
	}
	if !strings.HasPrefix(log, "mazebot: ignored a line longer than 64 KiB: {\"type\"") || len(log) > 300 {
		t.Fatalf("log: %q", log)
	}
	// The long line is skipped; the one of exactly MaxLine bytes is read.
	if out != `{"rotation":0,"movement":1}`+"\n"+`{"rotation":0,"movement":2}`+"\n" {
		t.Fatalf("%q", out)
	}
	if got := strings.Join(bot.senses, "|"); got != "[0 1 0] 0 2|[0 1 0] 0 3" {
		t.Fatalf("senses: %s", got)
	}
}

func TestServeBadLine(t *testing.T) {
	bot := &scripted{answers: []Answer{Move(0, 1)}}
	var log string
	out, err := serve(t, bot, "{\"type\":\"sense\",\"run\":0,\"step\":1,\"sensors\":[0,1,0]}\nnot json\n"+
		`{"type":"sense","run":0,"step":2,"sensors":[0,1,0]}`+"\n", &log)
	if err == nil || out != `{"rotation":0,"movement":1}`+"\n" {
		t.Fatalf("%q %v", out, err)
	}
	if log != "mazebot: cannot read a message (not a JSON object): not json\n" {
		t.Fatalf("log: %q", log)
	}
}

type failWriter struct{}

func (failWriter) Write([]byte) (int, error) { return 0, errors.New("broken pipe") }

func TestServeStopsWhenNobodyListens(t *testing.T) {
	bot := &scripted{answers: []Answer{Move(0, 1)}}
	err := Serve(bot, strings.NewReader(strings.Repeat(`{"type":"sense","run":0,"step":1,"sensors":[0,1,0]}`+"\n", 2)), failWriter{})
	if err != nil || len(bot.senses) != 1 {
		t.Fatalf("%v, %d senses", err, len(bot.senses))
	}
}

func TestServeDebugChecks(t *testing.T) {
	var big Debug
	for i := 0; big.CellText(i, 0, strings.Repeat("z", 1000)) == nil; i++ {
	}
	withRaw := func(raw string) Answer { a := Move(0, 1); a.Debug = json.RawMessage(raw); return a }
	answers := []Answer{
		withRaw("{\n  \"text\": \"pretty\",\n  \"path\": [[0, 0], [0, 1]]\n}\n"), // compacted
		withRaw(`{"text":"unterminated}`),                                        // invalid JSON
		withRaw(`[1,2]`),                                                         // not an object
		withRaw("{\"text\":\"\xff\"}"),                                           // not UTF-8
		withRaw(`{"a":"` + strings.Repeat("a", DebugMax) + `"}`),                 // too big
		withRaw(`{} {}`),                                                         // two values
		Move(0, 1).WithDebug(&Debug{}),                                           // empty: nothing
		Reset().WithDebug(&big),
	}
	input := ""
	for i := range answers {
		input += fmt.Sprintf(`{"type":"sense","run":0,"step":%d,"sensors":[0,1,0]}`+"\n", i+1)
	}
	var log string
	out, err := serve(t, &scripted{answers: answers}, input, &log)
	if err != nil {
		t.Fatal(err)
	}
	// One line for each reason, the first time.
	if log != "mazebot: step 2: debug object not sent (not valid JSON)\n"+
		"mazebot: step 5: debug object of 16392 bytes, over 16384: not sent\n" {
		t.Fatalf("log: %q", log)
	}
	lines := strings.Split(strings.TrimSuffix(out, "\n"), "\n")
	if len(lines) != len(answers) {
		t.Fatalf("%d lines: %q", len(lines), out)
	}
	if lines[0] != `{"rotation":0,"movement":1,"debug":{"text":"pretty","path":[[0,0],[0,1]]}}` {
		t.Fatalf("compacted: %s", lines[0])
	}
	for i := 1; i <= 6; i++ {
		if lines[i] != `{"rotation":0,"movement":1}` {
			t.Errorf("line %d: %s", i, lines[i])
		}
	}
	if want := `{"reset":true,"debug":` + big.String() + "}"; lines[7] != want || len(big.JSON()) < DebugMax-1100 {
		t.Errorf("big debug: %d bytes", len(lines[7]))
	}
	for _, l := range lines {
		if !json.Valid([]byte(l)) {
			t.Errorf("invalid line %s", l)
		}
	}
}

func TestServeDebugMatchBudget(t *testing.T) {
	var d Debug
	d.Text(strings.Repeat("t", 4000))
	n := 20
	answers := make([]Answer, n)
	input := ""
	for i := range answers {
		answers[i] = Move(0, 1).WithDebug(&d)
		input += fmt.Sprintf(`{"type":"sense","run":0,"step":%d,"sensors":[0,1,0]}`+"\n", i+1)
	}
	var log string
	out, err := serve(t, &scripted{answers: answers}, input, &log)
	if err != nil {
		t.Fatal(err)
	}
	fits := DebugMatchMax / len(d.JSON()) // 16
	if log != fmt.Sprintf("mazebot: step %d: the match's debug objects reached 65536 bytes: no more are sent\n", fits+1) {
		t.Fatalf("log: %q", log)
	}
	with, total := 0, 0
	for _, l := range strings.Split(strings.TrimSuffix(out, "\n"), "\n") {
		if strings.Contains(l, "debug") {
			with++
			total += len(d.JSON())
		}
	}
	if with != fits || total > DebugMatchMax {
		t.Fatalf("%d debug objects, %d bytes", with, total)
	}
}

// --- Run keeps stdout private (in a child process: it changes file descriptors) --

type printingBot struct{ BaseBot }

func (printingBot) NextMove(sensors [3]int, run, step int) Answer {
	fmt.Println("printed by the bot")
	os.Stdout.WriteString("written to os.Stdout\n")
	var s string
	if n, _ := fmt.Scanln(&s); n != 0 {
		fmt.Fprintln(os.Stderr, "stdin was readable:", s)
	}
	return Move(0, step)
}

func TestHelperProcessRun(t *testing.T) {
	if os.Getenv("MAZEBOT_HELPER") != "1" {
		t.Skip("run by TestRunKeepsStdoutPrivate")
	}
	err := Run(printingBot{})
	fmt.Println("after Run")
	if err != nil {
		os.Exit(3)
	}
	os.Exit(0)
}

func TestRunKeepsStdoutPrivate(t *testing.T) {
	cmd := exec.Command(os.Args[0], "-test.run=^TestHelperProcessRun$")
	cmd.Env = append(os.Environ(), "MAZEBOT_HELPER=1")
	cmd.Stdin = strings.NewReader(`{"type":"start","maze_dim":12}` + "\n" +
		`{"type":"sense","run":0,"step":1,"sensors":[0,1,0]}` + "\n" +
		`{"type":"sense","run":0,"step":2,"sensors":[0,1,0]}` + "\n" +
		`{"type":"end","status":"finished"}` + "\n")
	var stdout, stderr bytes.Buffer
	cmd.Stdout, cmd.Stderr = &stdout, &stderr
	if err := cmd.Run(); err != nil {
		t.Fatalf("%v; stderr:\n%s", err, stderr.String())
	}
	if want := `{"rotation":0,"movement":1}` + "\n" + `{"rotation":0,"movement":2}` + "\n"; stdout.String() != want {
		t.Fatalf("stdout %q; stderr:\n%s", stdout.String(), stderr.String())
	}
	for _, s := range []string{"printed by the bot", "written to os.Stdout", "after Run"} {
		if strings.Count(stderr.String(), s) == 0 {
			t.Errorf("stderr lacks %q:\n%s", s, stderr.String())
		}
	}
	if strings.Contains(stderr.String(), "stdin was readable") {
		t.Errorf("the bot read the protocol from stdin:\n%s", stderr.String())
	}
}

// --- the debug builder --------------------------------------------------------------

// checkDebug fails unless d's JSON is valid, within DebugMax, and as long as d
// computes.
func checkDebug(t *testing.T, d *Debug) {
	t.Helper()
	j := d.JSON()
	if j == nil {
		return
	}
	if !json.Valid(j) || !utf8.Valid(j) || len(j) > DebugMax || len(j) != d.size(-1, 0, 0) {
		t.Fatalf("bad debug JSON (%d bytes, size %d): %.300s", len(j), d.size(-1, 0, 0), j)
	}
}

func TestDebugZero(t *testing.T) {
	var d Debug
	if d.JSON() != nil || d.String() != "" || Move(0, 1).WithDebug(&d).Debug != nil || Move(0, 1).WithDebug(nil).Debug != nil {
		t.Fatal("an empty Debug sends something")
	}
}

func TestDebugAllFields(t *testing.T) {
	var d Debug
	d.Textf("run %d: %s", 0, "go")
	d.Wall(2, 3, Right)
	d.Wall(0, 0, Up)
	d.CellInt(1, 1, -5)
	d.CellText(1, 2, "?")
	d.Grid(2, []int{0, 1, -1, 3}, -1)
	d.Color(0, 0, "#f80")
	d.Color(1, 0, "#00FF7a")
	d.Path([][2]int{{0, 0}, {0, 1}})
	d.Text("replaced")
	checkDebug(t, &d)
	want := `{"text":"replaced","walls":[[2,3,"right"],[0,0,"up"]],"cells":[[1,1,-5],[1,2,"?"]],` +
		`"grid":[[0,1],[null,3]],"colors":[[0,0,"#f80"],[1,0,"#00FF7a"]],"path":[[0,0],[0,1]]}`
	if got := d.String(); got != want || d.Dropped != 0 {
		t.Fatalf("got  %s\nwant %s (%d dropped)", got, want, d.Dropped)
	}
	a := Move(90, 2).WithDebug(&d)
	d.Clear()
	if string(a.Debug) != want || d.JSON() != nil {
		t.Fatal("WithDebug does not keep the object as it was")
	}
}

func TestDebugBadArguments(t *testing.T) {
	var d Debug
	for _, c := range []string{"", "#", "f80", "#f8", "#ff80", "#ff800", "#ff80000", "#gg0000", "red", "#f80\"", "##f80"} {
		if d.Color(0, 0, c) != ErrDebugArg {
			t.Errorf("colour %q accepted", c)
		}
	}
	if d.Wall(0, 0, Side(4)) != ErrDebugArg || d.Wall(0, 0, Side(-1)) != ErrDebugArg ||
		d.Grid(3, make([]int, 8), 0) != ErrDebugArg || d.Grid(-1, nil, 0) != ErrDebugArg ||
		d.Empty(Field(9)) != ErrDebugArg {
		t.Error("a bad argument was accepted")
	}
	if d.JSON() != nil || d.Dropped != 16 {
		t.Fatalf("%s, %d dropped", d.JSON(), d.Dropped)
	}
}

func TestDebugEmptyFields(t *testing.T) {
	var d Debug
	d.Wall(1, 1, Left)
	for f := FieldText; f < numFields; f++ {
		if err := d.Empty(f); err != nil {
			t.Fatal(err)
		}
		checkDebug(t, &d)
	}
	if got := d.String(); got != `{"text":"","walls":[],"cells":[],"grid":[],"colors":[],"path":[]}` {
		t.Fatal(got)
	}
	d.Clear()
	d.Path(nil)
	d.Wall(0, 1, Down)
	if got := d.String(); got != `{"walls":[[0,1,"down"]],"path":[]}` || !d.Has(FieldPath) || d.Has(FieldText) {
		t.Fatal(got)
	}
}

func TestDebugStrings(t *testing.T) {
	var d Debug
	s := "q\"b\\s/n\nr\rt\tnul\x00del\x7fbad\xff\xfeé€😀<&>\u2028"
	d.Text(s)
	d.CellText(0, 0, s)
	checkDebug(t, &d)
	var back struct {
		Text  string
		Cells [][3]interface{}
	}
	if err := json.Unmarshal(d.JSON(), &back); err != nil {
		t.Fatal(err)
	}
	want := strings.ToValidUTF8(s, "\ufffd\ufffd")
	if back.Text != want || back.Cells[0][2] != want {
		t.Fatalf("got %q\nwant %q", back.Text, want)
	}
	// Text is cut at 4 KiB, on a character boundary.
	d.Text(strings.Repeat("é", 3000))
	checkDebug(t, &d)
	if err := json.Unmarshal(d.JSON(), &back); err != nil || len(back.Text) != 4096 {
		t.Fatalf("%v, %d bytes", err, len(back.Text))
	}
	d.Text("a" + strings.Repeat("é", 3000))
	json.Unmarshal(d.JSON(), &back)
	if len(back.Text) != 4095 || !utf8.ValidString(back.Text) {
		t.Fatalf("%d bytes", len(back.Text))
	}
}

func TestDebugCap(t *testing.T) {
	var d Debug
	d.Text("walls until full")
	added := 0
	for x := 0; ; x++ {
		err := d.Wall(x, x*1000, Up)
		checkDebug(t, &d)
		if err == ErrDebugFull {
			break
		} else if err != nil {
			t.Fatal(err)
		}
		added++
	}
	if d.Dropped != 1 || len(d.JSON()) < DebugMax-30 {
		t.Fatalf("%d walls, %d bytes, %d dropped", added, len(d.JSON()), d.Dropped)
	}
	// Small items may still fit; big ones are refused; the object stays valid.
	if d.Grid(100, make([]int, 10000), -1) != ErrDebugFull || d.Path(make([][2]int, 5000)) != ErrDebugFull {
		t.Fatal("a big item went in")
	}
	checkDebug(t, &d)
	// Emptying the walls makes room again.
	if err := d.Empty(FieldWalls); err != nil {
		t.Fatal(err)
	}
	if err := d.Grid(16, make([]int, 256), -1); err != nil {
		t.Fatal(err)
	}
	checkDebug(t, &d)
	// A big grid alone (32x32 of 5-digit values) is within the cap or refused, never broken.
	d.Clear()
	vals := make([]int, 32*32)
	for i := range vals {
		vals[i] = 10000 + i
	}
	err := d.Grid(32, vals, -1)
	checkDebug(t, &d)
	if (err == nil) != (6*32*32+2*32+1 <= DebugMax) {
		t.Fatal(err)
	}
}
