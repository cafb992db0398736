// The bot page's script: fetches the logs of the listed failed matches and the build
// logs with the owner's token (pasted in the page, sent only to this server's API),
// and shows them as text.
(function () {
  var form = document.getElementById('owner-form');
  var out = document.getElementById('owner-logs');
  function token() { return document.getElementById('owner-token').value.trim(); }
  function block(title, text) {
    var h = document.createElement('h3'); h.textContent = title; out.appendChild(h);
    var pre = document.createElement('pre'); pre.className = 'log'; pre.textContent = text; out.appendChild(pre);
  }
  function get(url) {
    return fetch(url, { headers: { authorization: 'Bearer ' + token() } }).then(function (r) {
      return r.json().then(function (j) { if (!r.ok) { throw new Error(j.error ? j.error.message : r.status); } return j; });
    });
  }
  form.addEventListener('submit', function (e) {
    e.preventDefault();
    out.textContent = '';
    var rows = document.querySelectorAll('table.matches tbody tr');
    var failed = [];
    rows.forEach(function (tr) {
      var st = tr.querySelector('.status');
      if (st && ['finished', 'queued', 'running', 'step_limit'].indexOf(st.textContent) < 0) {
        failed.push(tr.querySelector('td a').textContent);
      }
    });
    if (failed.length === 0) { block('Logs', 'No failed match in the recent list.'); }
    failed.forEach(function (id) {
      get('/api/matches/' + id + '/log').then(function (j) {
        var text = j.redacted ? 'hidden maze: status ' + j.status + (j.step ? ' at step ' + j.step : '')
          : (j.error ? (j.error.reason || '') + (j.error.line ? '\noffending line: ' + j.error.line : '') + '\n\n' : '') + (j.stderr_tail || '');
        block('match ' + id + ' (' + j.status + ')', text);
      }).catch(function (err) { block('match ' + id, 'error: ' + err.message); });
    });
  });
  document.querySelectorAll('a.build-log').forEach(function (a) {
    a.addEventListener('click', function (e) {
      e.preventDefault();
      get('/api/bots/' + form.dataset.bot + '/versions/' + a.dataset.version + '/build-log').then(function (j) {
        block('build of version ' + j.version + ' (' + j.build_status + ')', j.build_log || '(no output yet)');
      }).catch(function (err) { block('build of version ' + a.dataset.version, 'error: ' + err.message + ' (paste the owner token above)'); });
    });
  });
})();
