-- The fair queue: when each lane was last served. A lane is one owner's single matches
-- ('o:' and the owner token's hash) or one tournament ('t:' and its id); the two classes
-- of lanes are lanes too ('class:s' for single matches, 'class:t' for tournaments). The
-- next match claimed is the first waiting match of the lane least recently served, in
-- the class least recently served. `served` is a counter, not a time: one more than the
-- largest at each claim.
create table queue_lane (
    lane text primary key,
    served bigint not null
);

-- The waiting single matches (a few per owner, however many tournament matches wait),
-- for finding each owner's first one without reading the whole queue.
create index match_waiting_single on match (bot_id, match_id)
    where status = 'queued' and tournament_id is null;
