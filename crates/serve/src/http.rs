//! HTTP: a fixed set of routes, the access check in front of all of them,
//! and the page.
//!
//! - `GET /` — the page (one HTML file, script and style inline);
//! - `GET /ws` — the websocket of one tab (see `session`);
//! - `GET /frame.png?width=W&height=H` — the latest view, converged.
//!
//! Nothing is read from the file system by path: every other path —
//! `/../etc/passwd`, its percent-encoded forms, `//etc/passwd` — is 404.
//! When the server is bound beyond loopback every request must carry the
//! access token (`?token=…`, or the `x-voxless-token` header): missing is
//! 401, wrong is 403. On loopback, requests must name a loopback host (so a
//! web page cannot reach the server by DNS rebinding), and a request a page
//! makes (it carries an `Origin`) must come from the server's own origin:
//! scheme, host and port; `Origin: null` is refused.

use std::sync::Arc;

use axum::Router;
use axum::extract::ws::WebSocketUpgrade;
use axum::extract::{Query, Request, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use serde::Deserialize;

use crate::app::App;
use crate::protocol::{MAX_MESSAGE_BYTES, MAX_VIEW_SIDE};

/// The page, embedded in the binary.
pub const PAGE: &str = include_str!("page.html");

/// The router of the fixed routes behind the access check.
pub fn router(app: Arc<App>) -> Router {
    Router::new()
        .route("/", get(page))
        .route("/ws", get(websocket))
        .route("/frame.png", get(frame_png))
        .fallback(not_found)
        .layer(middleware::from_fn_with_state(app.clone(), access))
        .with_state(app)
}

async fn not_found() -> Response {
    (StatusCode::NOT_FOUND, "not found\n").into_response()
}

/// The token of a request: `?token=` or the `x-voxless-token` header.
fn request_token(req: &Request) -> Option<String> {
    let from_query = req.uri().query().and_then(|q| {
        q.split('&')
            .find_map(|kv| kv.strip_prefix("token="))
            .map(String::from)
    });
    from_query.or_else(|| {
        req.headers()
            .get("x-voxless-token")
            .and_then(|v| v.to_str().ok())
            .map(String::from)
    })
}

/// Compares without an early exit, so timing says nothing about the token.
fn same(a: &str, b: &str) -> bool {
    a.len() == b.len() && a.bytes().zip(b.bytes()).fold(0u8, |d, (x, y)| d | (x ^ y)) == 0
}

/// The host name of a Host header or origin (without port and scheme).
fn host_name(s: &str) -> &str {
    let s = s.split("://").last().unwrap_or(s);
    let s = s.split('/').next().unwrap_or(s);
    if let Some(rest) = s.strip_prefix('[') {
        return rest.split(']').next().unwrap_or(rest);
    }
    s.rsplit_once(':').map_or(s, |(h, _)| h)
}

/// Whether `origin` (`http://host:port`) is this server as `host` (the
/// Host header, `host:port`) names it.
fn same_origin(origin: &str, host: &str) -> bool {
    let Some(authority) = origin
        .strip_prefix("http://")
        .or_else(|| origin.strip_prefix("https://"))
    else {
        return false;
    };
    !host.is_empty() && authority.trim_end_matches('/').eq_ignore_ascii_case(host)
}

fn is_loopback_name(h: &str) -> bool {
    h.eq_ignore_ascii_case("localhost")
        || h.parse::<std::net::IpAddr>()
            .is_ok_and(|ip| ip.is_loopback())
}

/// The access check in front of every route (see the module docs).
async fn access(State(app): State<Arc<App>>, req: Request, next: Next) -> Response {
    let headers = req.headers();
    let host = headers
        .get(header::HOST)
        .and_then(|h| h.to_str().ok())
        .unwrap_or("");
    if app.loopback && !is_loopback_name(host_name(host)) {
        return (
            StatusCode::FORBIDDEN,
            "this server answers loopback hosts only\n",
        )
            .into_response();
    }
    // A browser names the page behind a request in `Origin`: only the
    // viewer's own page (scheme, host and port of this server) may drive
    // it. `null` (sandboxed frames, files) and other ports of the same host
    // are other pages. Requests without an Origin are not from a page.
    if let Some(origin) = headers.get(header::ORIGIN)
        && !same_origin(origin.to_str().unwrap_or("null"), host)
    {
        return (StatusCode::FORBIDDEN, "cross-origin requests are refused\n").into_response();
    }
    if let Some(token) = &app.token {
        match request_token(&req) {
            None => {
                return (
                    StatusCode::UNAUTHORIZED,
                    "an access token is required: open the URL the server printed\n",
                )
                    .into_response();
            }
            Some(t) if !same(&t, token) => {
                return (StatusCode::FORBIDDEN, "wrong access token\n").into_response();
            }
            Some(_) => {}
        }
    }
    let mut res = next.run(req).await;
    let h = res.headers_mut();
    // The token travels in the URL: never hand it to another site.
    h.insert(
        header::REFERRER_POLICY,
        HeaderValue::from_static("no-referrer"),
    );
    h.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    res
}

async fn page() -> Response {
    let mut headers = HeaderMap::new();
    headers.insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("text/html; charset=utf-8"),
    );
    headers.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static(
            "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; \
             img-src 'self' blob: data:; connect-src 'self'; base-uri 'none'; form-action 'none'",
        ),
    );
    (headers, PAGE).into_response()
}

async fn websocket(State(app): State<Arc<App>>, ws: WebSocketUpgrade) -> Response {
    ws.max_message_size(MAX_MESSAGE_BYTES)
        .max_frame_size(MAX_MESSAGE_BYTES)
        .on_upgrade(move |socket| crate::session::run(socket, app))
}

#[derive(Deserialize)]
struct FrameQuery {
    width: Option<u32>,
    height: Option<u32>,
    #[allow(dead_code)]
    token: Option<String>,
}

/// How many `/frame.png` renders run at once.
const FRAME_PNG_AT_ONCE: usize = 2;
static FRAME_PNG_TURNS: tokio::sync::Semaphore =
    tokio::sync::Semaphore::const_new(FRAME_PNG_AT_ONCE);

/// Cancels its token when dropped (the request's future going away).
struct CancelOnDrop(voxless::CancelToken);

impl Drop for CancelOnDrop {
    fn drop(&mut self) {
        self.0.cancel();
    }
}

async fn frame_png(
    State(app): State<Arc<App>>,
    query: Result<Query<FrameQuery>, axum::extract::rejection::QueryRejection>,
) -> Response {
    let Ok(Query(q)) = query else {
        return (
            StatusCode::BAD_REQUEST,
            "width and height must be whole numbers\n",
        )
            .into_response();
    };
    for (name, v) in [("width", q.width), ("height", q.height)] {
        if let Some(v) = v
            && !(1..=MAX_VIEW_SIDE).contains(&v)
        {
            let msg = format!("{name} {v} is outside 1..={MAX_VIEW_SIDE}\n");
            return (StatusCode::BAD_REQUEST, msg).into_response();
        }
    }
    // At most FRAME_PNG_AT_ONCE renders at a time (each holds a film of up
    // to 4096²); a client that drops while waiting costs nothing.
    let Ok(_turn) = FRAME_PNG_TURNS.acquire().await else {
        return (StatusCode::SERVICE_UNAVAILABLE, "shutting down\n").into_response();
    };
    // A client that drops mid-render drops this future, and with it the
    // guard, which cancels the render at its next tile.
    let cancel = voxless::CancelToken::new();
    let _guard = CancelOnDrop(cancel.clone());
    let result = tokio::task::spawn_blocking(move || {
        let png = crate::render::frame_png(&app, q.width, q.height, &cancel);
        // Nobody awaits a dropped request's render: say here that it
        // stopped (its film freed), so a terminal shows where the core went.
        if cancel.is_cancelled() {
            let size = match (q.width, q.height) {
                (Some(w), Some(h)) => format!(" {w}×{h}"),
                _ => String::new(),
            };
            eprintln!("note: a /frame.png{size} render stopped: its client left");
        }
        png
    })
    .await;
    match result {
        Ok(Ok(png)) => ([(header::CONTENT_TYPE, "image/png")], png).into_response(),
        Ok(Err(e)) => (StatusCode::UNPROCESSABLE_ENTITY, format!("{e}\n")).into_response(),
        Err(_) => (StatusCode::INTERNAL_SERVER_ERROR, "render failed\n").into_response(),
    }
}
