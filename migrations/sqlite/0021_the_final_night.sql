-- mazearena schema, version 21: the final night. A competition may hold its results after
-- the final run until its organiser publishes them (state 'held': the results are
-- written, seen by the organisers only; 'final' once published). Never edit an applied
-- migration: add a new file.
alter table competition add column hold_results integer not null default 0;
