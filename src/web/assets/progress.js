// A tournament page's live progress: polls the tournament's JSON every two seconds
// until it is complete, then reloads once to show the final tables.
(function () {
  var box = document.getElementById('progress');
  var id = box.dataset.tournament, total = +box.dataset.total, done = +box.dataset.done;
  var bar = document.getElementById('progress-bar');
  bar.style.width = bar.dataset.pct + '%';
  if (done >= total) { return; }
  var timer = setInterval(function () {
    fetch('/api/tournaments/' + id).then(function (r) { return r.json(); }).then(function (t) {
      box.dataset.done = t.done;
      document.getElementById('progress-bar').style.width = (t.total ? Math.floor(t.done * 100 / t.total) : 100) + '%';
      document.getElementById('progress-text').textContent = t.done + ' of ' + t.total + ' matches played';
      if (t.done >= t.total) { clearInterval(timer); location.reload(); }
    }).catch(function () {});
  }, 2000);
})();
