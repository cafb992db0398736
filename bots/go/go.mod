module mazebot

go 1.19
