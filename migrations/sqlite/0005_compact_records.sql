-- mazearena schema, version 5: a match's record stored compactly, apart from the match
-- row. Never edit an applied migration: add a new file.
--
-- `match.record` now holds only the summary that lists and pages need (no stderr tail,
-- no notices); the whole record, with its trace, is one compressed value here (see
-- src/storage/records.rs for the encodings). `match.trace` is no longer written: the
-- server converts the records of earlier versions when it opens the database (and
-- empties their `trace`). A match without a row here has only its summary (a match the
-- server ended without playing it, e.g. aborted).

create table match_record (
    match_id integer primary key references match (match_id) on delete cascade,
    -- 1: the whole record as JSON; 2: the answers only, the rest replayed on the maze
    encoding integer not null,
    -- zstd-compressed
    data blob not null
);

-- The rows still to convert, found without reading the table (empty once converted).
create index match_inline_trace on match (match_id) where trace is not null;
