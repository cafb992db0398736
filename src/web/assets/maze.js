/* mazearena's maze layouts in the browser, shared by the replay viewer and the final
 * night's shows (each page's one inline script begins with this file). */
var mazearenaLayout = (function () {
  'use strict';

  /** The task's numeric layout -> {n, open: Uint8Array (index x*n+y)} or null. */
  function parse(layout) {
    if (typeof layout !== 'string') return null;
    var lines = layout.split(/\r?\n/).map(function (l) { return l.trim(); }).filter(function (l) { return l !== ''; });
    var n = parseInt(lines[0], 10);
    if (!(n >= 2 && n <= 64) || lines.length < n + 1) return null;
    var open = new Uint8Array(n * n);
    for (var x = 0; x < n; x++) {
      var vals = lines[x + 1].split(',');
      if (vals.length < n) return null;
      for (var y = 0; y < n; y++) {
        var v = Number(vals[y].trim());
        if (!(Number.isInteger(v) && v >= 0 && v <= 15)) return null;
        open[x * n + y] = v;
      }
    }
    return { n: n, open: open };
  }

  return { parse: parse };
})();
