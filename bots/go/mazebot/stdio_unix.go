//go:build linux || darwin || dragonfly || freebsd || netbsd || openbsd

package mazebot

import (
	"io"
	"os"
	"syscall"
)

// privateStdio returns private copies of the real stdin and stdout for the
// protocol, then points file descriptor 1 at stderr (so os.Stdout, fmt.Println
// and child processes write to the bot's log) and file descriptor 0 at
// /dev/null. The copies are closed on exec: child processes never see the
// protocol. If the descriptors cannot be copied, the protocol keeps the real
// ones and only the os.Stdout variable is pointed at stderr.
func privateStdio() (io.Reader, io.Writer) {
	inFd, err := syscall.Dup(0)
	if err != nil {
		return fallbackStdio()
	}
	outFd, err := syscall.Dup(1)
	if err != nil {
		syscall.Close(inFd)
		return fallbackStdio()
	}
	syscall.CloseOnExec(inFd)
	syscall.CloseOnExec(outFd)
	if dupTo(2, 1) != nil {
		syscall.Close(inFd)
		syscall.Close(outFd)
		return fallbackStdio()
	}
	if devnull, err := os.Open(os.DevNull); err == nil {
		_ = dupTo(int(devnull.Fd()), 0)
		devnull.Close()
	}
	return os.NewFile(uintptr(inFd), "protocol-stdin"), os.NewFile(uintptr(outFd), "protocol-stdout")
}
