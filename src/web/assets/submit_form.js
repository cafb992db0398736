// The submit form: when files are chosen, the list of the robot's file offers the
// uploaded .py files and preselects robot.py, or else the only one that defines
// `class Robot` (read here, in the browser; the server checks the same). Without this
// script the server finds the file itself.
(function () {
  var input = document.querySelector('form.submit input[name=files]');
  var select = document.getElementById('robot-file');
  if (!input || !select) { return; }
  var defines = /^class Robot\s*[(:]/m;
  input.addEventListener('change', function () {
    var files = Array.prototype.filter.call(input.files, function (f) { return /\.py$/.test(f.name); });
    Promise.all(files.map(function (f) {
      return f.text().then(function (t) { return { name: f.name, robot: defines.test(t) }; });
    })).then(function (found) {
      while (select.options.length > 1) { select.remove(1); }
      found.sort(function (a, b) { return a.name < b.name ? -1 : 1; });
      var robots = found.filter(function (f) { return f.robot; });
      var chosen = found.some(function (f) { return f.name === 'robot.py'; }) ? 'robot.py'
        : (robots.length === 1 ? robots[0].name : '');
      found.forEach(function (f) {
        var o = document.createElement('option');
        o.value = f.name;
        o.textContent = f.name + (f.robot ? ' (defines class Robot)' : '');
        o.selected = f.name === chosen;
        select.appendChild(o);
      });
      if (chosen && robots.length > 0) {
        var box = document.querySelector('form.submit input[name=original_task]');
        if (box) { box.checked = true; }
      }
    });
  });
})();
