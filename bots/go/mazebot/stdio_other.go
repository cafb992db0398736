//go:build !(linux || darwin || dragonfly || freebsd || netbsd || openbsd)

package mazebot

import "io"

// privateStdio, where file descriptors cannot be copied: see fallbackStdio.
func privateStdio() (io.Reader, io.Writer) {
	return fallbackStdio()
}
