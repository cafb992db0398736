package mazebot

import "syscall"

// dupTo makes newfd a copy of oldfd (dup3: linux/arm64 and others have no dup2).
func dupTo(oldfd, newfd int) error {
	return syscall.Dup3(oldfd, newfd, 0)
}
