// dcc.Input takes no aria-label: each value's input gets its accessible name from its name
// attribute (instance.parameter), as the page's inputs appear and change
(function () {
  function label(root) {
    root.querySelectorAll("input[name]:not([aria-label])").forEach(function (el) {
      el.setAttribute("aria-label", el.getAttribute("name"));
    });
  }
  new MutationObserver(function () { label(document); })
    .observe(document.documentElement, {childList: true, subtree: true});
  document.addEventListener("DOMContentLoaded", function () { label(document); });
})();

// A request the server does not answer (it was stopped, or this tab outlived it): said in the
// alert, rather than a progress bar that stays where it was
(function () {
  var realFetch = window.fetch;
  window.fetch = function () {
    return realFetch.apply(this, arguments).catch(function (err) {
      var alert = document.getElementById("alert");
      if (alert) {
        alert.textContent = "the app's server does not answer: it was stopped (start it " +
          "again with `sewfmu app`, then reload this page)";
      }
      throw err;
    });
  };
})();
