/* mazearena's final night: the reveal of a competition's results from the last place to
 * the first, and the race of every robot on one maze. Reads one JSON document from
 * <script type="application/json" id="finale-data">: {kind: "reveal", reveal: {...}} or
 * {kind: "race", race: {...}}. Loads nothing, talks to nobody: the same script plays
 * on the server's pages and in the offline files. */
(function () {
  'use strict';

  var dataEl = document.getElementById('finale-data');
  var root = document.getElementById('finale');
  if (!dataEl || !root) return;
  var data;
  try { data = JSON.parse(dataEl.textContent); } catch (e) { root.textContent = 'The data of this page cannot be read.'; return; }

  function el(tag, attrs, parent, text) {
    var e = document.createElement(tag);
    if (attrs) for (var k in attrs) if (Object.prototype.hasOwnProperty.call(attrs, k)) {
      if (k === 'class') e.className = attrs[k]; else e.setAttribute(k, attrs[k]);
    }
    if (text != null) e.textContent = text;
    if (parent) parent.appendChild(e);
    return e;
  }

  var parseLayout = mazearenaLayout.parse;

  function colour(i) { return 'hsl(' + Math.round((i * 137.508) % 360) + ', 72%, 42%)'; }
  function fmtScore(s) { return s == null ? '' : Number(s).toFixed(3); }

  /* ---------------- the race player ---------------- */

  var SPEEDS = [5, 10, 20, 50, 100, 200];

  function RacePlayer(host, race, opts) {
    opts = opts || {};
    var maze = parseLayout(race.layout);
    var n = race.dim;
    var runners = race.runners;
    var F0 = 0, F1 = 0;
    runners.forEach(function (r) { F0 = Math.max(F0, r.run0.length - 1); F1 = Math.max(F1, r.run1.length - 1); });
    var last = F0 + 1 + F1;
    var frame = 0, playing = false, speed = 20, acc = 0, lastT = 0, raf = 0;

    var box = el('section', { 'class': 'fn-race', 'aria-label': 'Race: ' + race.title }, host);
    var level = opts.level || 1;
    el('h' + level, { 'class': 'fn-race-title' }, box, race.title);
    var sub = el('p', { 'class': 'fn-sub' }, box, runners.length + (runners.length === 1 ? ' robot' : ' robots') + ', one seed (' + race.seed + ')' +
      (race.optimal ? '; the optimal run 1 takes ' + race.optimal.steps + ' steps' : ''));
    if (race.organiser_copy) el('p', { 'class': 'fn-warn' }, box, 'This maze is one the competition keeps hidden: an organiser\u2019s copy, not to be shared.');
    var body = el('div', { 'class': 'fn-race-body' }, box);
    var stage = el('div', { 'class': 'fn-stage' }, body);
    var canvas = el('canvas', { 'class': 'fn-canvas', width: '640', height: '640', role: 'img', 'aria-label': 'The maze with every robot on it' }, stage);
    var controls = el('div', { 'class': 'fn-controls' }, stage);
    var bBack = el('button', { type: 'button', 'class': 'fn-back', title: 'Step back (Left arrow)' }, controls, '\u25C0 Back');
    var bPlay = el('button', { type: 'button', 'class': 'fn-play fn-primary', title: 'Play / pause (Space)' }, controls, '\u25B6 Play');
    var bFwd = el('button', { type: 'button', 'class': 'fn-forward', title: 'Step forward (Right arrow)' }, controls, 'Forward \u25B6');
    var slider = el('input', { type: 'range', 'class': 'fn-slider', min: '0', max: String(last), value: '0', step: '1', 'aria-label': 'Step' }, controls);
    var stepNum = el('span', { 'class': 'fn-stepnum', 'aria-live': 'off' }, controls);
    var controls2 = el('div', { 'class': 'fn-controls' }, stage);
    var speedLabel = el('label', null, controls2, 'Speed ');
    var speedSel = el('select', { 'class': 'fn-speed' }, speedLabel);
    SPEEDS.forEach(function (s) { var o = el('option', { value: String(s) }, speedSel, s + ' steps/s'); if (s === speed) o.selected = true; });
    var bRun1 = el('button', { type: 'button', 'class': 'fn-run1' }, controls2, 'Jump to run 1');
    var optLabel = el('label', null, controls2);
    var optBox = el('input', { type: 'checkbox', 'class': 'fn-optimal' }, optLabel);
    optLabel.appendChild(document.createTextNode(' Optimal route'));
    if (!race.optimal) optBox.disabled = true;
    var trailLabel = el('label', null, controls2);
    var trailBox = el('input', { type: 'checkbox', 'class': 'fn-trails' }, trailLabel);
    trailBox.checked = true;
    trailLabel.appendChild(document.createTextNode(' Trails'));
    var side = el('div', { 'class': 'fn-side' }, body);
    el('h' + (level + 1), null, side, 'Standing');
    var standing = el('ol', { 'class': 'fn-standing', 'aria-live': 'polite' }, side);
    var legend = el('details', { 'class': 'fn-legend' }, side);
    el('summary', null, legend, 'Robots and colours');
    var legendList = el('ul', null, legend);
    runners.forEach(function (r, i) {
      var li = el('li', null, legendList);
      var sw = el('span', { 'class': 'fn-swatch' }, li);
      sw.style.background = colour(i);
      li.appendChild(document.createTextNode(' ' + r.name + ' (' + r.bot + ')'));
    });

    var S = 640, cell = S / n;
    var base = document.createElement('canvas'), trails = document.createElement('canvas');
    base.width = base.height = trails.width = trails.height = S;
    var ctx = canvas.getContext('2d'), bctx = base.getContext('2d'), tctx = trails.getContext('2d');
    function px(x) { return (x + 0.5) * cell; }
    function py(y) { return (n - y - 0.5) * cell; }

    (function drawBase() {
      bctx.fillStyle = '#ffffff'; bctx.fillRect(0, 0, S, S);
      var a = n / 2 - 1;
      bctx.fillStyle = '#dcfce7';
      bctx.fillRect(a * cell, (n - a - 2) * cell, 2 * cell, 2 * cell);
      bctx.fillStyle = '#dbeafe';
      bctx.fillRect(0, (n - 1) * cell, cell, cell);
      bctx.strokeStyle = '#e5e7eb'; bctx.lineWidth = 1;
      bctx.beginPath();
      for (var i = 1; i < n; i++) { bctx.moveTo(i * cell, 0); bctx.lineTo(i * cell, S); bctx.moveTo(0, i * cell); bctx.lineTo(S, i * cell); }
      bctx.stroke();
      bctx.strokeStyle = '#1f2937'; bctx.lineWidth = Math.max(2, cell * 0.08); bctx.lineCap = 'square';
      bctx.beginPath();
      if (maze) {
        var open = maze.open;
        for (var x = 0; x < n; x++) for (var y = 0; y < n; y++) {
          var v = open[x * n + y];
          if (y < n - 1 && (!(v & 1) || !(open[x * n + y + 1] & 4))) { bctx.moveTo(x * cell, (n - y - 1) * cell); bctx.lineTo((x + 1) * cell, (n - y - 1) * cell); }
          if (x < n - 1 && (!(v & 2) || !(open[(x + 1) * n + y] & 8))) { bctx.moveTo((x + 1) * cell, (n - y - 1) * cell); bctx.lineTo((x + 1) * cell, (n - y) * cell); }
        }
      }
      bctx.rect(0, 0, S, S);
      bctx.stroke();
    })();

    // Each runner's trail is drawn a little off the cell's centre, so that trails that
    // share a corridor stay apart.
    function off(i) { return ((i % 7) - 3) * cell * 0.05; }
    var trailRun = -1, trailStep = -1;
    function runAndStep(f) { return f <= F0 ? [0, f] : [1, f - F0 - 1]; }
    function pathOf(r, run) { return run === 0 ? r.run0 : r.run1; }
    function drawTrails(run, from, to) {
      tctx.lineWidth = Math.max(1.5, cell * 0.1); tctx.lineCap = 'round'; tctx.lineJoin = 'round';
      tctx.globalAlpha = 0.55;
      runners.forEach(function (r, i) {
        var p = pathOf(r, run);
        var a = Math.min(from, p.length - 1), b = Math.min(to, p.length - 1);
        if (b <= a) return;
        tctx.strokeStyle = colour(i);
        tctx.beginPath();
        tctx.moveTo(px(p[a][0]) + off(i), py(p[a][1]) + off(i));
        for (var k = a + 1; k <= b; k++) tctx.lineTo(px(p[k][0]) + off(i), py(p[k][1]) + off(i));
        tctx.stroke();
      });
      tctx.globalAlpha = 1;
    }
    function updateTrails(run, step) {
      if (run !== trailRun || step < trailStep) {
        tctx.clearRect(0, 0, S, S);
        trailRun = run; trailStep = 0;
      }
      if (step > trailStep) { drawTrails(run, trailStep, step); trailStep = step; }
    }

    var lastKey = '';
    function standingAt(run, step) {
      var rows = runners.map(function (r, i) {
        var p = pathOf(r, run), done = step >= p.length - 1;
        var o = { i: i, r: r, order: 3, key: 0, text: '' };
        if (run === 0) {
          if (r.goal0 != null && r.goal0 <= step) { o.order = 0; o.key = r.goal0; o.text = 'reached the goal at step ' + r.goal0; }
          else if (done && r.run0_steps != null) { o.order = 1; o.key = r.run0_steps; o.text = 'reset at step ' + r.run0_steps; }
          else if (done) { o.order = 2; o.text = r.status.replace(/_/g, ' '); }
          else o.text = 'exploring';
        } else {
          if (r.run1_steps != null && r.run1_steps <= step) { o.order = 0; o.key = r.run1_steps * 100000 + (r.score30 || 0); o.text = 'goal at step ' + r.run1_steps + ', score ' + fmtScore(r.score); }
          else if (done && r.status !== 'finished') { o.order = 2; o.text = r.status.replace(/_/g, ' '); }
          else o.text = 'running';
        }
        return o;
      });
      rows.sort(function (a, b) { return a.order - b.order || a.key - b.key || (a.r.rank || 0) - (b.r.rank || 0) || (a.r.name < b.r.name ? -1 : a.r.name > b.r.name ? 1 : 0); });
      return rows;
    }
    function renderStanding(run, step) {
      var rows = standingAt(run, step);
      var key = run + '|' + rows.map(function (o) { return o.i + ':' + o.text; }).join('|');
      if (key === lastKey) return;
      lastKey = key;
      standing.textContent = '';
      rows.forEach(function (o, place) {
        var li = el('li', { 'class': 'fn-row fn-row-' + (o.order === 0 ? 'goal' : o.order === 2 ? 'out' : 'on'), 'data-name': o.r.name, 'data-place': String(place + 1) }, standing);
        var sw = el('span', { 'class': 'fn-swatch' }, li);
        sw.style.background = colour(o.i);
        el('span', { 'class': 'fn-row-name' }, li, ' ' + o.r.name);
        el('span', { 'class': 'fn-row-text' }, li, ' \u2014 ' + o.text);
      });
    }

    function draw() {
      var rs = runAndStep(frame), run = rs[0], step = rs[1];
      ctx.drawImage(base, 0, 0);
      if (trailBox.checked) { updateTrails(run, step); ctx.drawImage(trails, 0, 0); }
      if (optBox.checked && race.optimal) {
        ctx.save(); ctx.setLineDash([cell * 0.2, cell * 0.15]); ctx.strokeStyle = '#16a34a'; ctx.lineWidth = Math.max(2, cell * 0.12);
        ctx.beginPath();
        race.optimal.path.forEach(function (c, k) { if (k === 0) ctx.moveTo(px(c[0]), py(c[1])); else ctx.lineTo(px(c[0]), py(c[1])); });
        ctx.stroke(); ctx.restore();
      }
      var rad = Math.max(2.5, cell * (runners.length > 20 ? 0.16 : 0.26));
      runners.forEach(function (r, i) {
        var p = pathOf(r, run), c = p[Math.min(step, p.length - 1)];
        ctx.beginPath();
        ctx.arc(px(c[0]) + off(i), py(c[1]) + off(i), rad, 0, 2 * Math.PI);
        ctx.fillStyle = colour(i); ctx.fill();
        ctx.lineWidth = 1; ctx.strokeStyle = '#ffffff'; ctx.stroke();
      });
      slider.value = String(frame);
      stepNum.textContent = 'run ' + run + ', step ' + step + ' / ' + (run === 0 ? F0 : F1);
      box.setAttribute('data-run', String(run));
      box.setAttribute('data-step', String(step));
      box.setAttribute('data-frame', String(frame));
      renderStanding(run, step);
    }

    function go(f) { frame = Math.max(0, Math.min(last, f)); draw(); if (frame >= last) pause(); }
    function tick(t) {
      if (!playing) return;
      if (lastT) acc += (t - lastT) / 1000 * speed;
      lastT = t;
      var whole = Math.floor(acc);
      if (whole > 0) { acc -= whole; go(frame + whole); }
      if (playing) raf = requestAnimationFrame(tick);
    }
    function play() { if (frame >= last) frame = 0; playing = true; acc = 0; lastT = 0; bPlay.textContent = '\u275A\u275A Pause'; box.setAttribute('data-playing', 'true'); raf = requestAnimationFrame(tick); }
    function pause() { playing = false; cancelAnimationFrame(raf); bPlay.textContent = '\u25B6 Play'; box.setAttribute('data-playing', 'false'); }
    bPlay.addEventListener('click', function () { if (playing) pause(); else play(); });
    bBack.addEventListener('click', function () { pause(); go(frame - 1); });
    bFwd.addEventListener('click', function () { pause(); go(frame + 1); });
    bRun1.addEventListener('click', function () { go(F0 + 1); });
    slider.addEventListener('input', function () { go(Number(slider.value)); });
    speedSel.addEventListener('change', function () { speed = Number(speedSel.value) || 20; });
    optBox.addEventListener('change', draw);
    trailBox.addEventListener('change', draw);
    box.tabIndex = 0;
    box.addEventListener('keydown', function (ev) {
      if (ev.target && (ev.target.tagName === 'SELECT' || ev.target.tagName === 'INPUT' && ev.target.type === 'range')) return;
      if (ev.key === 'ArrowRight') { pause(); go(frame + 1); }
      else if (ev.key === 'ArrowLeft') { pause(); go(frame - 1); }
      else if (ev.key === ' ') { if (playing) pause(); else play(); }
      else if (ev.key === 'Home') go(0);
      else if (ev.key === 'End') go(last);
      else return;
      ev.preventDefault(); ev.stopPropagation();
    });
    draw();
    if (opts.autoplay) play();
    return { play: play, pause: pause, go: go, last: last, destroy: function () { pause(); host.textContent = ''; } };
  }

  /* ---------------- the reveal ---------------- */

  function Reveal(host, rv) {
    // Groups of equal rank, the last place first.
    var groups = [];
    rv.lines.forEach(function (l) {
      var g = groups.length && groups[groups.length - 1][0].rank === l.rank ? groups[groups.length - 1] : null;
      if (g) g.push(l); else groups.push([l]);
    });
    groups.reverse();
    var shown = 0, auto = null;

    var head = el('header', { 'class': 'fn-head' }, host);
    el('h1', null, head, rv.title);
    el('p', { 'class': 'fn-sub' }, head, 'The final results, revealed from the last place to the first: ' + rv.lines.length + (rv.lines.length === 1 ? ' entrant' : ' entrants') + '.');
    if (!rv.published) el('p', { 'class': 'fn-warn fn-rehearsal' }, head, 'Rehearsal: the results are held. Only the competition\u2019s organisers see this page until they publish them.');
    if (rv.organiser_copy) el('p', { 'class': 'fn-warn fn-organiser-copy' }, head, 'This reveal draws private mazes the competition keeps hidden: an organiser\u2019s copy, not to be shared.');
    if (rv.private_hidden) el('p', { 'class': 'fn-sub fn-hidden-note' }, head, 'The private mazes stay hidden: no match on them is shown.');
    var bar = el('div', { 'class': 'fn-controls fn-reveal-controls' }, host);
    var bBack = el('button', { type: 'button', id: 'reveal-back', title: 'Back (Left arrow)' }, bar, '\u25C0 Back');
    var bNext = el('button', { type: 'button', id: 'reveal-next', 'class': 'fn-primary', title: 'Next (Right arrow or Space)' }, bar, 'Reveal the last place \u25B6');
    var autoLabel = el('label', null, bar, 'Pace ');
    var pace = el('select', { id: 'reveal-pace' }, autoLabel);
    [['0', 'by hand'], ['3', 'every 3 s'], ['5', 'every 5 s'], ['8', 'every 8 s']].forEach(function (p) { el('option', { value: p[0] }, pace, p[1]); });
    var counter = el('span', { 'class': 'fn-stepnum', id: 'reveal-count' }, bar);
    var stageBox = el('section', { 'class': 'fn-current', id: 'reveal-current', 'aria-live': 'polite' }, host);
    var table = el('table', { 'class': 'fn-table', id: 'reveal-table' }, host);
    var hr = el('tr', null, el('thead', null, table));
    ['Rank', 'Entrant', 'Bot', 'Mean score', 'Finished', 'Public rank', 'Moved', 'Best match', 'Worst match'].forEach(function (h) { el('th', { scope: 'col' }, hr, h); });
    var tbody = el('tbody', null, table);
    var dialog = el('dialog', { 'class': 'fn-dialog', id: 'reveal-play' }, host);
    var dClose = el('button', { type: 'button', 'class': 'fn-close' }, dialog, 'Close');
    var dHost = el('div', null, dialog);
    var player = null;
    dClose.addEventListener('click', function () { dialog.close(); });
    dialog.addEventListener('close', function () { if (player) { player.destroy(); player = null; } });

    function movedText(l) {
      if (l.moved == null) return 'not on the public board';
      if (l.moved > 0) return 'up ' + l.moved + (l.moved === 1 ? ' place' : ' places');
      if (l.moved < 0) return 'down ' + (-l.moved) + (l.moved === -1 ? ' place' : ' places');
      return 'held its place';
    }
    function movedClass(l) { return l.moved == null ? 'fn-moved-none' : l.moved > 0 ? 'fn-moved-up' : l.moved < 0 ? 'fn-moved-down' : 'fn-moved-same'; }
    function playButton(parent, m, label) {
      if (!m) { el('span', { 'class': 'fn-sub' }, parent, '\u2014'); return; }
      var text = label + ': ' + m.maze + ', seed ' + (m.repeat + 1) + ' \u2014 ' + (m.score != null ? fmtScore(m.score) : m.status.replace(/_/g, ' '));
      if (rv.plays[String(m.match_id)]) {
        var b = el('button', { type: 'button', 'class': 'fn-play-match', 'data-match': String(m.match_id) }, parent, '\u25B6 ' + text);
        b.addEventListener('click', function () { openPlay(m.match_id); });
      } else el('span', null, parent, text);
    }
    function openPlay(id) {
      var race = rv.plays[String(id)];
      if (!race) return;
      stopAuto();
      dHost.textContent = '';
      player = RacePlayer(dHost, race, { autoplay: true, level: 2 });
      if (dialog.showModal) dialog.showModal(); else dialog.setAttribute('open', '');
    }
    function cardFor(group) {
      stageBox.textContent = '';
      var tie = group.length > 1;
      stageBox.setAttribute('data-rank', String(group[0].rank));
      el('p', { 'class': 'fn-place' }, stageBox, (tie ? 'Tied for place ' : 'Place ') + group[0].rank);
      group.forEach(function (l) {
        var card = el('article', { 'class': 'fn-card reveal-entrant', 'data-entrant': l.entrant, 'data-rank': String(l.rank), 'data-moved': l.moved == null ? '' : String(l.moved) }, stageBox);
        el('h2', null, card, l.entrant);
        el('p', { 'class': 'fn-sub' }, card, l.bot_name + ' v' + l.version);
        var dl = el('dl', { 'class': 'fn-facts' }, card);
        function fact(k, v, cls) { var d = el('div', cls ? { 'class': cls } : null, dl); el('dt', null, d, k); el('dd', null, d, v); }
        fact('Mean score', fmtScore(l.mean_score));
        fact('Finished', l.finished + ' of ' + l.played);
        fact('Public rank', l.public_rank == null ? '\u2014' : String(l.public_rank));
        fact('Moved', movedText(l), 'reveal-moved ' + movedClass(l));
        var plays = el('p', { 'class': 'fn-plays' }, card);
        playButton(plays, l.best, 'Best');
        playButton(plays, l.worst, 'Worst');
      });
    }
    function rowFor(l) {
      var tr = document.createElement('tr');
      tr.setAttribute('data-entrant', l.entrant);
      tr.setAttribute('data-rank', String(l.rank));
      [String(l.rank), l.entrant, l.bot_name + ' v' + l.version, fmtScore(l.mean_score), l.finished + '/' + l.played,
        l.public_rank == null ? '\u2014' : String(l.public_rank)].forEach(function (t) { el('td', null, tr, t); });
      el('td', { 'class': movedClass(l) }, tr, movedText(l));
      playButton(el('td', null, tr), l.best, 'Best');
      playButton(el('td', null, tr), l.worst, 'Worst');
      return tr;
    }
    function render() {
      tbody.textContent = '';
      // Revealed so far: the best of them on top, as a results table reads.
      for (var g = shown - 1; g >= 0; g--) groups[g].forEach(function (l) { tbody.appendChild(rowFor(l)); });
      if (shown === 0) {
        stageBox.textContent = '';
        stageBox.removeAttribute('data-rank');
        el('p', { 'class': 'fn-place' }, stageBox, groups.length ? 'Ready.' : 'No results.');
      } else cardFor(groups[shown - 1]);
      host.setAttribute('data-shown', String(shown));
      counter.textContent = shown + ' of ' + groups.length + (groups.length === 1 ? ' place' : ' places') + ' revealed';
      bBack.disabled = shown === 0;
      bNext.disabled = shown >= groups.length;
      bNext.textContent = shown >= groups.length ? 'All revealed' : shown === groups.length - 1 ? 'Reveal the winner \u25B6' : shown === 0 ? 'Reveal the last place \u25B6' : 'Next \u25B6';
      if (shown >= groups.length) stopAuto();
    }
    function next() { if (shown < groups.length) { shown++; render(); } }
    function back() { if (shown > 0) { shown--; render(); } }
    function stopAuto() { if (auto) { clearInterval(auto); auto = null; } pace.value = '0'; }
    bNext.addEventListener('click', next);
    bBack.addEventListener('click', function () { stopAuto(); back(); });
    pace.addEventListener('change', function () {
      if (auto) { clearInterval(auto); auto = null; }
      var s = Number(pace.value);
      if (s > 0) auto = setInterval(next, s * 1000);
    });
    document.addEventListener('keydown', function (ev) {
      if (dialog.open) return;
      if (ev.target && /^(INPUT|SELECT|TEXTAREA|BUTTON)$/.test(ev.target.tagName) && ev.key === ' ') return;
      if (ev.key === 'ArrowRight' || ev.key === ' ' || ev.key === 'PageDown') { next(); ev.preventDefault(); }
      else if (ev.key === 'ArrowLeft' || ev.key === 'PageUp') { stopAuto(); back(); ev.preventDefault(); }
    });
    if (rv.races && rv.races.length && opts_links) {
      var nav = el('nav', { 'class': 'fn-races', 'aria-label': 'Races' }, host);
      el('h2', null, nav, 'Races: every robot on one maze');
      var ul = el('ul', null, nav);
      rv.races.forEach(function (r) { var li = el('li', null, ul); el('a', { href: r.path }, li, r.maze + ', seed ' + (r.repeat + 1) + ' (' + r.set + ')'); });
    }
    render();
  }

  var opts_links = root.getAttribute('data-online') === 'true';
  if (data.kind === 'reveal') Reveal(root, data.reveal);
  else if (data.kind === 'race') RacePlayer(root, data.race, {});
})();
