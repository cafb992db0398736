// The competition page's script: fetches the entrant's submissions and quotas with the
// key pasted in the page (sent only to this server's API) and shows them as text.
(function () {
  var form = document.getElementById('mine-form');
  var out = document.getElementById('mine');
  function el(tag, text, cls) {
    var e = document.createElement(tag);
    if (text !== undefined) { e.textContent = text; }
    if (cls) { e.className = cls; }
    return e;
  }
  form.addEventListener('submit', function (e) {
    e.preventDefault();
    out.textContent = '';
    var key = document.getElementById('mine-key').value.trim();
    fetch('/api/competitions/' + encodeURIComponent(form.dataset.competition) + '/submissions',
          { headers: { authorization: 'Bearer ' + key } })
      .then(function (r) {
        return r.json().then(function (j) { if (!r.ok) { throw new Error(j.error ? j.error.message : r.status); } return j; });
      })
      .then(function (j) {
        out.appendChild(el('p', j.versions_quota.message, 'quota'));
        out.appendChild(el('p', j.practice_quota.message, 'quota'));
        if (j.final_result) {
          var f = j.final_result;
          out.appendChild(el('p', 'Final result: rank ' + f.rank + ' with version ' + f.version +
            ', mean score ' + f.mean_score.toFixed(3) + ' over ' + f.played + ' private matches (' +
            f.finished + ' finished).', 'final-result'));
        }
        if (j.bot_id === null) { out.appendChild(el('p', 'No bot entered yet.', 'muted')); return; }
        var table = el('table', undefined, 'data submissions');
        var head = el('tr');
        ['version', 'uploaded', 'build', 'status', 'public rank', 'public mean', 'finished'].forEach(function (h) { head.appendChild(el('th', h)); });
        table.appendChild(el('thead')).appendChild(head);
        var body = el('tbody');
        j.versions.forEach(function (v) {
          var tr = el('tr');
          [String(v.version), v.uploaded_at, v.build_status, v.status,
           v.public ? String(v.public.rank) : '-',
           v.public ? v.public.mean_score.toFixed(3) : '-',
           v.public ? v.public.finished + '/' + v.public.played : '-'].forEach(function (t) { tr.appendChild(el('td', t)); });
          body.appendChild(tr);
        });
        table.appendChild(body);
        out.appendChild(table);
      })
      .catch(function (err) { out.appendChild(el('p', 'error: ' + err.message, 'error')); });
  });
})();
