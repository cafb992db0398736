// Package mazebot is the protocol side of a mazearena bot written in Go.
//
// The server talks to a bot through line-delimited JSON on stdin and stdout
// (docs/PROTOCOL.md). This package does all of it, so that a bot is a type
// with three methods and a call to Run:
//
//	type myBot struct{ n int }
//
//	func (b *myBot) Start(info mazebot.StartInfo) { b.n = info.MazeDim }
//
//	func (b *myBot) NextMove(sensors [3]int, run, step int) mazebot.Answer {
//		if sensors[1] > 0 {
//			return mazebot.Move(0, 1) // straight on, one cell
//		}
//		return mazebot.Move(90, 0) // turn right on the spot
//	}
//
//	func (b *myBot) End(info mazebot.EndInfo) { fmt.Println("result:", info.Status) }
//
//	func main() {
//		if err := mazebot.Run(&myBot{}); err != nil {
//			os.Exit(1)
//		}
//	}
//
// The methods (embed BaseBot to get empty Start and End):
//
//   - Start(info): once, before the first move. info.MazeDim is the side of the
//     maze; info.Seed is there so that a randomized bot can be made reproducible.
//   - NextMove(sensors, run, step): once per step. sensors is {left, front, right}:
//     open cells to the nearest wall, relative to the heading. run is 0
//     (exploration) or 1 (the timed run); step is the shared 1-based step counter.
//     Return Move(rotation, movement) (rotation -90, 0 or 90 degrees, clockwise
//     positive, applied first; movement -3..3 cells, negative = backward) or
//     Reset() (ends run 0; only accepted once the robot has ended a move in the
//     goal room during run 0).
//   - End(info): once, with the server's final message.
//
// Printing is safe: while Run is active, file descriptor 1 (os.Stdout, so
// fmt.Println, and any child process given os.Stdout) is a copy of stderr,
// which the server keeps as the bot's log and never reads; the protocol goes
// through private copies of the real stdin and stdout, and each answer is
// written with a single write call, so nothing is left in a buffer. Standard
// input reads /dev/null, so nothing can eat the server's messages by accident.
//
// Debug drawing (docs/PROTOCOL.md, "Debug drawing"): an answer may carry a
// debug object that the replay viewer draws over the maze. Build it with a
// Debug and attach it to the answer:
//
//	var d mazebot.Debug
//	d.Textf("run %d: %d steps to go", run, steps)
//	d.Wall(2, 3, mazebot.Right)
//	d.Grid(n, dist, inf) // dist[x*n+y]; inf is sent as null
//	return mazebot.Move(0, 1).WithDebug(&d)
//
// Input lines may be up to MaxLine bytes (a longer one is logged and skipped).
// Messages are parsed with encoding/json: any field order, any whitespace,
// unknown fields of any type and a trailing "\r" are fine, and unknown message
// types are ignored.
package mazebot

import (
	"bufio"
	"bytes"
	"encoding/json"
	"errors"
	"fmt"
	"io"
	"math"
	"os"
	"strconv"
	"unicode/utf8"
)

// logOutput receives the package's own log lines (tests change it).
var logOutput io.Writer = os.Stderr

// MaxLine is the longest input line read, not counting its "\n" (the
// protocol's 64 KiB).
const MaxLine = 65536

// StartInfo is the start message.
type StartInfo struct {
	Protocol      int    // 1
	MazeDim       int    // side of the maze, e.g. 12
	MaxSteps      int    // 1000
	Seed          uint64 // for reproducible randomness
	MoveTimeoutMs int    // time per answer, in milliseconds
}

// EndInfo is the end message. A field the server sent as null (or did not
// send) is nil.
type EndInfo struct {
	Status    string   // "finished", "step_limit", "timeout", "crashed", "protocol_error", ...
	Score     *float64 // run-1 steps + run-0 steps / 30; nil unless finished
	Run0Steps *int     // nil until a reset was accepted
	Run1Steps *int     // nil unless finished
}

// Answer is one answer to a sense message: a move, or a reset (then Rotation
// and Movement are not sent).
type Answer struct {
	Rotation int  // -90, 0 or 90
	Movement int  // -3 .. 3
	Reset    bool // true: {"reset":true}
	// Debug is an optional debug object for the replay viewer: the JSON of one
	// object, usually set with WithDebug. Run checks it (valid UTF-8, one JSON
	// object, at most DebugMax bytes once compacted) and leaves it out, with a
	// line on stderr, when it is not, so a bad debug object never costs the match.
	Debug json.RawMessage
}

// Move is the answer: turn by rotation degrees (-90, 0 or 90), then move
// movement cells (-3 .. 3, negative = backward, without turning).
func Move(rotation, movement int) Answer {
	return Answer{Rotation: rotation, Movement: movement}
}

// Reset is the answer that ends run 0 (accepted once the robot has ended a move
// in the goal room during run 0).
func Reset() Answer {
	return Answer{Reset: true}
}

// WithDebug returns a with d's object attached (its JSON as it is now: d may be
// changed or cleared afterwards). A nil d, or one with no field set, attaches
// nothing.
func (a Answer) WithDebug(d *Debug) Answer {
	a.Debug = nil
	if d != nil {
		a.Debug = d.JSON()
	}
	return a
}

// Bot is what Run calls. Embed BaseBot in a bot that needs no Start or End.
type Bot interface {
	// Start is called once, before the first move.
	Start(info StartInfo)
	// NextMove is called once per step and returns the answer.
	NextMove(sensors [3]int, run, step int) Answer
	// End is called once, with the server's final message.
	End(info EndInfo)
}

// BaseBot has empty Start and End methods, for embedding.
type BaseBot struct{}

// Start does nothing.
func (BaseBot) Start(StartInfo) {}

// End does nothing.
func (BaseBot) End(EndInfo) {}

// MessageType tells which message ParseMessage read.
type MessageType int

// The message types.
const (
	MsgOther MessageType = iota // a type this package does not know: ignored
	MsgStart
	MsgSense
	MsgEnd
)

// Message is one message from the server, as ParseMessage reads it.
type Message struct {
	Type    MessageType
	Start   StartInfo // MsgStart
	Sensors [3]int    // MsgSense: left, front, right
	Run     int       // MsgSense: 0 or 1
	Step    int       // MsgSense: 1 .. 1000
	End     EndInfo   // MsgEnd
}

// ParseMessage reads one JSON line (without its "\n"). Unknown fields are
// skipped whatever their type, a known field holding a value of another type
// counts as absent, and a message of an unknown type is MsgOther. It returns an
// error when the line is not one JSON object, or when a start message has no
// maze_dim or a sense message lacks run or its three sensors.
func ParseMessage(line []byte) (Message, error) {
	msg := Message{Start: StartInfo{Protocol: 1, MaxSteps: 1000, MoveTimeoutMs: 1000}}
	trimmed := bytes.TrimSpace(line)
	if len(trimmed) == 0 || trimmed[0] != '{' {
		return msg, errors.New("not a JSON object")
	}
	var fields map[string]json.RawMessage
	if err := json.Unmarshal(trimmed, &fields); err != nil {
		return msg, err
	}
	var typ string
	if raw, ok := fields["type"]; ok && len(raw) > 0 && raw[0] == '"' {
		if err := json.Unmarshal(raw, &typ); err != nil {
			return msg, err
		}
	}
	intField := func(key string, dst *int) bool {
		v, ok := number(fields[key])
		if ok {
			*dst = clampInt(v)
		}
		return ok
	}
	switch typ {
	case "start":
		msg.Type = MsgStart
		intField("protocol", &msg.Start.Protocol)
		intField("max_steps", &msg.Start.MaxSteps)
		intField("move_timeout_ms", &msg.Start.MoveTimeoutMs)
		if v, ok := number(fields["seed"]); ok {
			// A negative seed is taken modulo 2^64; one of 2^63 or more is read
			// again as unsigned (saturated at 2^64-1).
			msg.Start.Seed = uint64(v)
			if v == math.MaxInt64 {
				msg.Start.Seed = math.MaxUint64
				if s, err := strconv.ParseUint(string(bytes.TrimSpace(fields["seed"])), 10, 64); err == nil {
					msg.Start.Seed = s
				}
			}
		}
		if !intField("maze_dim", &msg.Start.MazeDim) {
			return msg, errors.New("start message without maze_dim")
		}
	case "sense":
		msg.Type = MsgSense
		intField("step", &msg.Step)
		var sensors []json.RawMessage
		raw := fields["sensors"]
		okSensors := len(raw) > 0 && raw[0] == '[' && json.Unmarshal(raw, &sensors) == nil &&
			len(sensors) == 3
		for i := 0; okSensors && i < 3; i++ {
			if v, ok := number(sensors[i]); ok {
				msg.Sensors[i] = clampInt(v)
			}
		}
		if !intField("run", &msg.Run) || !okSensors {
			return msg, errors.New("sense message without run or three sensors")
		}
	case "end":
		msg.Type = MsgEnd
		if raw, ok := fields["status"]; ok && len(raw) > 0 && raw[0] == '"' {
			_ = json.Unmarshal(raw, &msg.End.Status) // valid: checked with the line
		}
		if raw := bytes.TrimSpace(fields["score"]); isNumber(raw) {
			if f, err := strconv.ParseFloat(string(raw), 64); err == nil || isRangeError(err) {
				msg.End.Score = &f
			}
		}
		var r0, r1 int
		if intField("run0_steps", &r0) {
			msg.End.Run0Steps = &r0
		}
		if intField("run1_steps", &r1) {
			msg.End.Run1Steps = &r1
		}
	}
	return msg, nil
}

// isNumber says whether raw is a JSON number (and not null, a string, ...).
func isNumber(raw []byte) bool {
	return len(raw) > 0 && (raw[0] == '-' || (raw[0] >= '0' && raw[0] <= '9'))
}

func isRangeError(err error) bool {
	var ne *strconv.NumError
	return errors.As(err, &ne) && ne.Err == strconv.ErrRange
}

// number reads a JSON number as an int64: saturated when it is too large,
// rounded toward zero when it has a fraction or an exponent. ok is false for
// anything that is not a number (absent, null, a string, ...).
func number(raw json.RawMessage) (v int64, ok bool) {
	raw = bytes.TrimSpace(raw)
	if !isNumber(raw) {
		return 0, false
	}
	s := string(raw)
	if i, err := strconv.ParseInt(s, 10, 64); err == nil {
		return i, true
	} else if isRangeError(err) {
		if raw[0] == '-' {
			return math.MinInt64, true
		}
		return math.MaxInt64, true
	}
	f, err := strconv.ParseFloat(s, 64)
	if err != nil && !isRangeError(err) {
		return 0, false
	}
	switch {
	case f >= math.MaxInt64:
		return math.MaxInt64, true
	case f <= math.MinInt64:
		return math.MinInt64, true
	}
	return int64(f), true
}

// clampInt converts v to an int, saturating where int is 32 bits.
func clampInt(v int64) int {
	if v > math.MaxInt {
		return math.MaxInt
	}
	if v < math.MinInt {
		return math.MinInt
	}
	return int(v)
}

// Run plays one match over the process's stdin and stdout (made private, see
// the package comment). It returns nil after the end message or when stdin
// closes (or the server stops reading the answers), and an error, already
// written to stderr, after a line it cannot read, so
//
//	if err := mazebot.Run(bot); err != nil {
//		os.Exit(1)
//	}
//
// gives the right exit status.
func Run(bot Bot) error {
	in, out := privateStdio()
	return Serve(bot, in, out)
}

// Serve plays one match over in and out (Run's loop, exposed for tests and for
// bots that handle their own streams). Each answer is one Write to out.
func Serve(bot Bot, in io.Reader, out io.Writer) error {
	if bot == nil {
		fmt.Fprintln(logOutput, "mazebot: Serve needs a bot")
		return errors.New("mazebot: no bot")
	}
	r := bufio.NewReaderSize(in, 64*1024)
	var line []byte
	var debug debugBudget
	for {
		var tooLong bool
		var err error
		line, tooLong, err = readLine(r, line)
		if err != nil && err != io.EOF {
			logLine("cannot read stdin ("+err.Error()+")", line)
			return err
		}
		if err == io.EOF && len(line) == 0 && !tooLong {
			return nil // the server closed our stdin
		}
		text := bytes.TrimRight(line, " \t\r")
		switch {
		case tooLong:
			logLine("ignored a line longer than 64 KiB", text)
		case len(text) == 0:
		default:
			msg, perr := ParseMessage(text)
			if perr != nil {
				logLine("cannot read a message ("+perr.Error()+")", text)
				return fmt.Errorf("mazebot: cannot read a message: %w", perr)
			}
			switch msg.Type {
			case MsgStart:
				bot.Start(msg.Start)
			case MsgSense:
				a := bot.NextMove(msg.Sensors, msg.Run, msg.Step)
				if _, werr := out.Write(appendAnswer(nil, a, debug.check(a.Debug, msg.Step))); werr != nil {
					return nil // the server stopped listening: nothing left to do
				}
			case MsgEnd:
				bot.End(msg.End)
				return nil
			}
			// other message types: ignored (room for later protocol versions)
		}
		if err == io.EOF {
			return nil
		}
	}
}

// readLine reads one line into buf (reused), without its "\n". A line longer
// than MaxLine is consumed whole and reported as tooLong, with only its start
// kept (for the log).
func readLine(r *bufio.Reader, buf []byte) (line []byte, tooLong bool, err error) {
	buf = buf[:0]
	for {
		chunk, err := r.ReadSlice('\n')
		if err == nil {
			chunk = chunk[:len(chunk)-1]
		}
		if !tooLong && len(buf)+len(chunk) <= MaxLine {
			buf = append(buf, chunk...)
		} else {
			tooLong = true
			if keep := 200 - len(buf); keep > 0 {
				buf = append(buf, chunk[:min(keep, len(chunk))]...)
			}
		}
		if err != bufio.ErrBufferFull {
			return buf, tooLong, err
		}
	}
}

func min(a, b int) int {
	if a < b {
		return a
	}
	return b
}

// appendAnswer appends a's JSON line (with debug, already checked, if not nil).
func appendAnswer(b []byte, a Answer, debug []byte) []byte {
	if a.Reset {
		b = append(b, `{"reset":true`...)
	} else {
		b = append(b, `{"rotation":`...)
		b = strconv.AppendInt(b, int64(a.Rotation), 10)
		b = append(b, `,"movement":`...)
		b = strconv.AppendInt(b, int64(a.Movement), 10)
	}
	if debug != nil {
		b = append(b, `,"debug":`...)
		b = append(b, debug...)
	}
	return append(b, "}\n"...)
}

// debugBudget checks the debug objects of one match against the server's
// limits, and says on stderr (once for each reason) when one is left out.
type debugBudget struct {
	sent                        int
	warnedBad, warnedBig, match bool
}

// check returns the compact JSON of raw to send, or nil.
func (d *debugBudget) check(raw json.RawMessage, step int) []byte {
	if raw == nil {
		return nil
	}
	var buf bytes.Buffer
	problem := ""
	switch {
	case !utf8.Valid(raw):
		problem = "not UTF-8"
	case json.Compact(&buf, raw) != nil:
		problem = "not valid JSON"
	case buf.Len() == 0 || buf.Bytes()[0] != '{':
		problem = "not a JSON object"
	}
	switch {
	case problem != "":
		if !d.warnedBad {
			d.warnedBad = true
			fmt.Fprintf(logOutput, "mazebot: step %d: debug object not sent (%s)\n", step, problem)
		}
	case buf.Len() > DebugMax:
		if !d.warnedBig {
			d.warnedBig = true
			fmt.Fprintf(logOutput, "mazebot: step %d: debug object of %d bytes, over %d: not sent\n",
				step, buf.Len(), DebugMax)
		}
	case d.sent+buf.Len() > DebugMatchMax:
		if !d.match {
			d.match = true
			fmt.Fprintf(logOutput, "mazebot: step %d: the match's debug objects reached %d bytes: "+
				"no more are sent\n", step, DebugMatchMax)
		}
	default:
		d.sent += buf.Len()
		return buf.Bytes()
	}
	return nil
}

func logLine(what string, line []byte) {
	more := ""
	if len(line) > 200 {
		line, more = line[:200], "..."
	}
	fmt.Fprintf(logOutput, "mazebot: %s: %s%s\n", what, line, more)
}
