// The match page's script: with the owner token pasted in the form, fetches the match's
// replay and log from this server's API and hands their stderr to the viewer.
(function () {
  var form = document.getElementById('match-owner-form');
  var status = document.getElementById('match-owner-status');
  form.addEventListener('submit', function (e) {
    e.preventDefault();
    var id = form.dataset.match;
    var token = document.getElementById('match-owner-token').value.trim();
    var headers = { headers: { authorization: 'Bearer ' + token } };
    function get(url) {
      return fetch(url, headers).then(function (r) {
        return r.json().then(function (j) { if (!r.ok) { throw new Error(j.error ? j.error.message : r.status); } return j; });
      });
    }
    status.textContent = 'loading...';
    Promise.all([get('/api/matches/' + id + '/replay'), get('/api/matches/' + id + '/log')]).then(function (both) {
      if (!both[0].stderr_shown) { throw new Error('this token is not the bot owner\'s'); }
      window.mazearenaViewer.showStderr(both[0].trace, both[1].stderr_tail || '');
      status.textContent = "The bot's stderr is shown in the viewer.";
    }).catch(function (err) { status.textContent = 'Cannot show the stderr: ' + err.message; });
  });
})();
