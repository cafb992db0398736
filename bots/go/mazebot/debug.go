package mazebot

import (
	"errors"
	"fmt"
	"strconv"
	"unicode/utf8"
)

// The server keeps at most DebugMax bytes of one step's debug JSON, and
// DebugMatchMax bytes of a whole match's. Run sends nothing beyond them (one
// line on stderr says so).
const (
	DebugMax      = 16 * 1024
	DebugMatchMax = 64 * 1024
)

// maxText is where Text cuts its string.
const maxText = 4096

// Side is a side of a cell, for Debug.Wall: the same numbers as mazemap's
// directions Up .. Left (clockwise).
type Side int

// The sides of a cell.
const (
	Up Side = iota
	Right
	Down
	Left
)

var sideNames = [4]string{"up", "right", "down", "left"}

// Field is one field of a debug object, for Debug.Empty.
type Field int

// The fields of a debug object, in the order they are written.
const (
	FieldText Field = iota
	FieldWalls
	FieldCells
	FieldGrid
	FieldColors
	FieldPath
	numFields
)

var fieldKeys = [numFields]string{"text", "walls", "cells", "grid", "colors", "path"}

// isList says whether f is sent as a list of items that calls add to (walls,
// cells, colors); the others hold one value that each call replaces.
func (f Field) isList() bool {
	return f == FieldWalls || f == FieldCells || f == FieldColors
}

// The errors of the Debug methods: the item was left out (and Dropped counts it).
var (
	ErrDebugFull = errors.New("mazebot: the debug object would go over 16 KiB")
	ErrDebugArg  = errors.New("mazebot: bad debug argument")
)

// Debug builds a debug object: what the bot believes, drawn by the replay
// viewer at this step. (0, 0) is the bottom-left cell, x to the right, y up.
// Every field is optional and sticky in the viewer (each shows the latest one
// sent), so send big ones only when they change. The zero value is an empty
// object, ready to use.
//
// The builder always yields valid JSON: strings are escaped, and bytes that are
// not UTF-8 become U+FFFD. An item that would take the object over DebugMax
// bytes is left out: the method returns ErrDebugFull and Dropped counts it.
type Debug struct {
	fields  [numFields]debugField
	Dropped int // items left out since the last Clear
}

type debugField struct {
	present bool
	items   [][]byte // each item's JSON (one for a one-value field)
	bytes   int      // their total length
}

// Clear empties d (call it at the start of every step, or use a new Debug).
func (d *Debug) Clear() {
	*d = Debug{}
}

// size is the length of the object's JSON if field f had items of total
// length bytes (count of them).
func (d *Debug) size(f Field, bytes, count int) int {
	n, fields := 2, 0
	for g := Field(0); g < numFields; g++ {
		b, c, present := d.fields[g].bytes, len(d.fields[g].items), d.fields[g].present
		if g == f {
			b, c, present = bytes, count, true
		}
		if !present {
			continue
		}
		fields++
		n += len(fieldKeys[g]) + 3 + b // "key":
		if g.isList() {
			n += 2 // []
			if c > 1 {
				n += c - 1 // commas
			}
		}
	}
	if fields > 1 {
		n += fields - 1
	}
	return n
}

// add keeps item as one of f's items (for a one-value field, instead of its
// earlier value), if the object stays within DebugMax bytes.
func (d *Debug) add(f Field, item []byte) error {
	fd := &d.fields[f]
	bytes, count := len(item), 1
	if f.isList() {
		bytes += fd.bytes
		count += len(fd.items)
	}
	if d.size(f, bytes, count) > DebugMax {
		d.Dropped++
		return ErrDebugFull
	}
	if f.isList() {
		fd.items = append(fd.items, item)
	} else {
		fd.items = [][]byte{item}
	}
	fd.present, fd.bytes = true, bytes
	return nil
}

func (d *Debug) bad() error {
	d.Dropped++
	return ErrDebugArg
}

// Text sets the line of text shown with the step (cut at 4 KiB).
func (d *Debug) Text(s string) error {
	if len(s) > maxText {
		cut := maxText
		for cut > 0 && !utf8.RuneStart(s[cut]) {
			cut--
		}
		s = s[:cut]
	}
	return d.add(FieldText, appendString(nil, s))
}

// Textf sets the line of text shown with the step, fmt.Sprintf-style.
func (d *Debug) Textf(format string, args ...interface{}) error {
	return d.Text(fmt.Sprintf(format, args...))
}

func appendCell(b []byte, x, y int) []byte {
	b = append(b, '[')
	b = strconv.AppendInt(b, int64(x), 10)
	b = append(b, ',')
	return strconv.AppendInt(b, int64(y), 10)
}

// Wall adds a wall the bot believes in, on side (Up .. Left) of cell (x, y).
func (d *Debug) Wall(x, y int, side Side) error {
	if side < Up || side > Left {
		return d.bad()
	}
	b := appendCell(nil, x, y)
	b = append(b, `,"`...)
	b = append(b, sideNames[side]...)
	return d.add(FieldWalls, append(b, `"]`...))
}

// CellInt writes a number in cell (x, y).
func (d *Debug) CellInt(x, y, value int) error {
	b := append(appendCell(nil, x, y), ',')
	b = strconv.AppendInt(b, int64(value), 10)
	return d.add(FieldCells, append(b, ']'))
}

// CellText writes a short text in cell (x, y).
func (d *Debug) CellText(x, y int, text string) error {
	b := append(appendCell(nil, x, y), ',')
	b = appendString(b, text)
	return d.add(FieldCells, append(b, ']'))
}

// Grid sets values for the whole n x n maze: values[x*n+y] (the maze file's
// order, one column after another). A value equal to null is sent as null
// (nothing shown in that cell).
func (d *Debug) Grid(n int, values []int, null int) error {
	if n < 0 || len(values) < n*n {
		return d.bad()
	}
	b := make([]byte, 0, 2+n*(2+4*n))
	b = append(b, '[')
	for x := 0; x < n; x++ {
		if x > 0 {
			b = append(b, ',')
		}
		b = append(b, '[')
		for y := 0; y < n; y++ {
			if y > 0 {
				b = append(b, ',')
			}
			if v := values[x*n+y]; v == null {
				b = append(b, "null"...)
			} else {
				b = strconv.AppendInt(b, int64(v), 10)
			}
		}
		b = append(b, ']')
		if len(b) > DebugMax {
			break // too big anyway: add refuses it
		}
	}
	return d.add(FieldGrid, append(b, ']'))
}

// Color sets the colour of cell (x, y): "#rgb" or "#rrggbb" (anything else is
// refused with ErrDebugArg).
func (d *Debug) Color(x, y int, hex string) error {
	if !validColor(hex) {
		return d.bad()
	}
	b := append(appendCell(nil, x, y), `,"`...)
	b = append(b, hex...)
	return d.add(FieldColors, append(b, `"]`...))
}

func validColor(s string) bool {
	if (len(s) != 4 && len(s) != 7) || s[0] != '#' {
		return false
	}
	for i := 1; i < len(s); i++ {
		c := s[i]
		if !(c >= '0' && c <= '9' || c >= 'a' && c <= 'f' || c >= 'A' && c <= 'F') {
			return false
		}
	}
	return true
}

// Path sets a planned path through the listed cells, {x, y} each. An empty (or
// nil) path is sent as [], which clears the drawn one.
func (d *Debug) Path(cells [][2]int) error {
	b := make([]byte, 0, 2+8*len(cells))
	b = append(b, '[')
	for i, c := range cells {
		if i > 0 {
			b = append(b, ',')
		}
		b = append(appendCell(b, c[0], c[1]), ']')
		if len(b) > DebugMax {
			break // too big anyway: add refuses it
		}
	}
	return d.add(FieldPath, append(b, ']'))
}

// Empty sends field f empty ("text":"", or an empty list), which clears what
// the viewer shows for it, and drops the items already added to it.
func (d *Debug) Empty(f Field) error {
	if f < 0 || f >= numFields {
		return d.bad()
	}
	var item []byte
	count := 0
	switch {
	case f == FieldText:
		item, count = []byte(`""`), 1
	case !f.isList():
		item, count = []byte(`[]`), 1
	}
	if d.size(f, len(item), count) > DebugMax {
		d.Dropped++
		return ErrDebugFull
	}
	fd := &d.fields[f]
	fd.present, fd.bytes, fd.items = true, len(item), nil
	if item != nil {
		fd.items = [][]byte{item}
	}
	return nil
}

// Has says whether field f is set (possibly empty).
func (d *Debug) Has(f Field) bool {
	return f >= 0 && f < numFields && d.fields[f].present
}

// JSON returns the object's compact JSON (at most DebugMax bytes), or nil when
// no field is set.
func (d *Debug) JSON() []byte {
	var b []byte
	for f := Field(0); f < numFields; f++ {
		fd := &d.fields[f]
		if !fd.present {
			continue
		}
		if b == nil {
			b = make([]byte, 0, d.size(-1, 0, 0))
			b = append(b, '{')
		} else {
			b = append(b, ',')
		}
		b = append(b, '"')
		b = append(b, fieldKeys[f]...)
		b = append(b, `":`...)
		if f.isList() {
			b = append(b, '[')
		}
		for i, item := range fd.items {
			if i > 0 {
				b = append(b, ',')
			}
			b = append(b, item...)
		}
		if f.isList() {
			b = append(b, ']')
		}
	}
	if b == nil {
		return nil
	}
	return append(b, '}')
}

// String returns the object's JSON ("" when no field is set).
func (d *Debug) String() string {
	return string(d.JSON())
}

const hexDigits = "0123456789abcdef"

// appendString appends s as a JSON string: quotes, backslashes and control
// characters escaped, bytes that are not UTF-8 replaced by U+FFFD.
func appendString(b []byte, s string) []byte {
	b = append(b, '"')
	for i := 0; i < len(s); {
		r, size := utf8.DecodeRuneInString(s[i:])
		switch {
		case r == utf8.RuneError && size == 1:
			b = append(b, `\ufffd`...)
		case r == '"':
			b = append(b, `\"`...)
		case r == '\\':
			b = append(b, `\\`...)
		case r == '\n':
			b = append(b, `\n`...)
		case r == '\r':
			b = append(b, `\r`...)
		case r == '\t':
			b = append(b, `\t`...)
		case r < 0x20 || r == 0x7f:
			b = append(b, '\\', 'u', '0', '0', hexDigits[r>>4], hexDigits[r&0xf])
		default:
			b = append(b, s[i:i+size]...)
		}
		i += size
	}
	return append(b, '"')
}
