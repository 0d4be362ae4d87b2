// The page's requests to its server's API (viewer/server.py). Each carries the launch's secret
// token, read from this page's address (`?token=...`, as `skyscatter view` prints it; the server
// refuses API requests without it, header server.TOKEN_HEADER), and this page's own id (header
// server.CLIENT_HEADER: a newer table request of this page cancels its older ones, not another
// page's).

const TOKEN = new URLSearchParams(window.location.search).get("token") || "";
const CLIENT = Array.from(crypto.getRandomValues(new Uint8Array(12)),
                         (byte) => byte.toString(16).padStart(2, "0")).join("");

// fetch() of api/PATH with the token and the page's id
export function apiFetch(path) {
  return fetch(`api/${path}`, {headers: {"X-Skyscatter-Token": TOKEN, "X-Skyscatter-Client": CLIENT}});
}

// The JSON answer of api/PATH; throws an Error with the server's message (and .status) otherwise
export async function apiJson(path) {
  const response = await apiFetch(path);
  const answer = await response.json().catch(() => ({error: response.statusText}));
  if (!response.ok) {
    const error = new Error(answer.error);
    error.status = response.status;
    throw error;
  }
  return answer;
}
