package mazebot

import (
	"io"
	"os"
)

// realStdout keeps the original os.Stdout reachable once the variable points at
// stderr: an *os.File that is garbage collected closes its descriptor.
var realStdout *os.File

// fallbackStdio keeps the protocol on the real stdin and stdout and points the
// os.Stdout variable (fmt.Println, ...) at stderr.
func fallbackStdio() (io.Reader, io.Writer) {
	if realStdout == nil {
		realStdout = os.Stdout
	}
	os.Stdout = os.Stderr
	return os.Stdin, realStdout
}
