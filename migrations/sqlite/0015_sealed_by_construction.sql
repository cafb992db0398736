-- mazearena schema, version 15: sealed by construction.
--
-- A competition belongs to the organiser who made it (null: the admin's); other
-- organisers may not see what it seals or change it.
alter table competition add column organiser_id integer references organiser (organiser_id);

-- The private set is played only after the close, by the final run: the private-set
-- matches that competitions still open had waiting are dropped (those already played
-- stay, counted nowhere: the private board is the final run's).
delete from match
where status = 'queued'
    and tournament_id in (select private_tournament_id from competition
                          where state is null and private_tournament_id is not null);
