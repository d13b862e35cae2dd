// Sends the control API's bearer token (pymotoros sim --token) with every request of the
// pendant: asks for it once, on the first 401, and keeps it for this tab's session.
"use strict";
(function () {
  const KEY = "pymotoros-token";
  const token = () => sessionStorage.getItem(KEY);
  const realFetch = window.fetch.bind(window);
  async function withToken(input, init) {
    const t = token();
    const opts = Object.assign({}, init || {});
    if (t) opts.headers = Object.assign({}, opts.headers || {}, { Authorization: "Bearer " + t });
    return realFetch(input, opts);
  }
  let asking = null;
  function ask() {
    if (!asking) {
      asking = Promise.resolve().then(() => {
        const t = window.prompt("This twin's control API needs its token (pymotoros sim --token):");
        if (t) sessionStorage.setItem(KEY, t.trim());
        asking = null;
        return !!t;
      });
    }
    return asking;
  }
  window.fetch = async function (input, init) {
    const sentWith = token();
    const resp = await withToken(input, init);
    if (resp.status !== 401) return resp;
    // A request sent before the token was typed (several start at once) retries with
    // it; only a request that failed with the current token asks again.
    if (token() && token() !== sentWith) return withToken(input, init);
    if (await ask()) return withToken(input, init);
    return resp;
  };
  const RealWebSocket = window.WebSocket;
  window.WebSocket = function (url, protocols) {
    const t = token();
    if (t && String(url).indexOf("/ws/") >= 0) {
      const sep = String(url).indexOf("?") >= 0 ? "&" : "?";
      url = String(url) + sep + "access_token=" + encodeURIComponent(t);
    }
    return protocols === undefined ? new RealWebSocket(url) : new RealWebSocket(url, protocols);
  };
  window.WebSocket.prototype = RealWebSocket.prototype;
  for (const k of ["CONNECTING", "OPEN", "CLOSING", "CLOSED"]) {
    window.WebSocket[k] = RealWebSocket[k];
  }
  window.fetch("/api/state").catch(() => undefined);  // asks at once when a token is needed
})();
