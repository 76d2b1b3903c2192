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
