//! Bearer tokens, users and roles.
//!
//! Tokens come from a TOML file (`--auth FILE`):
//!
//! ```toml
//! [[token]]
//! token = "s3cret"
//! user = "alice"
//! role = "editor"      # viewer | editor | admin | render-node
//! ```
//!
//! or from the `NAADF_TOKENS` environment variable: `TOKEN=user:role` entries separated by
//! commas. With neither, the server runs open: every caller is an admin, named after its
//! bearer token if it sends one (so that tools still get per-user undo) or `anonymous`.

use serde::Deserialize;
use std::collections::HashMap;
use std::path::Path;
use tonic::Status;
use tonic::metadata::MetadataMap;

/// What a caller may do.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Role {
    /// Join and read only.
    Viewer,
    /// Join, edit, move entities, undo and redo.
    Editor,
    /// Everything, including the table ops (define_material, define_model).
    Admin,
    /// A headless render node: joins and serves frames.
    RenderNode,
}

impl Role {
    /// The role's name as configured.
    pub fn name(self) -> &'static str {
        match self {
            Role::Viewer => "viewer",
            Role::Editor => "editor",
            Role::Admin => "admin",
            Role::RenderNode => "render-node",
        }
    }

    /// The role named `s` (as configured and as `Status` reports it), if there is one.
    pub fn parse(s: &str) -> Option<Role> {
        [Role::Viewer, Role::Editor, Role::Admin, Role::RenderNode]
            .into_iter()
            .find(|r| r.name() == s)
    }
}

/// An authenticated caller.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Caller {
    /// The user name (undo history and retries are per user).
    pub user: String,
    /// The role.
    pub role: Role,
}

impl Caller {
    /// The user name as a message quotes it: in open mode it is the caller's own token,
    /// of any length.
    pub fn quoted_user(&self) -> String {
        naadf_world::ops::clip_input(&self.user, naadf_world::ops::MAX_QUOTED_CHARS)
    }

    /// Fails with PERMISSION_DENIED unless the caller's role is one of `allowed`; the
    /// message says what the caller tried (`action`) and which roles may.
    fn require(&self, allowed: &[Role], action: &str) -> Result<(), Status> {
        if allowed.contains(&self.role) {
            return Ok(());
        }
        let names: Vec<_> = allowed.iter().map(|r| r.name()).collect();
        Err(Status::permission_denied(format!(
            "user '{}' has role {}, which cannot {action} ({} needed)",
            self.quoted_user(),
            self.role.name(),
            names.join(" or ")
        )))
    }

    /// Fails with PERMISSION_DENIED unless the caller may edit.
    pub fn require_editor(&self) -> Result<(), Status> {
        self.require(&[Role::Editor, Role::Admin], "edit")
    }

    /// Fails with PERMISSION_DENIED unless the caller may serve frames (render-node or
    /// admin).
    pub fn require_render_node(&self) -> Result<(), Status> {
        self.require(&[Role::RenderNode, Role::Admin], "register a render node")
    }

    /// Fails with PERMISSION_DENIED unless the caller is an admin.
    pub fn require_admin(&self, what: &str) -> Result<(), Status> {
        if self.role == Role::Admin {
            return Ok(());
        }
        Err(Status::permission_denied(format!(
            "user '{}' has role {}; {what} needs admin",
            self.quoted_user(),
            self.role.name()
        )))
    }
}

/// The token table (empty: open mode).
///
/// It holds the tokens' SHA-256 digests, never the tokens: a lookup hashes the presented
/// token and compares digests, so the time a wrong guess takes depends on how its digest
/// compares, which says nothing about any valid token (hash, then compare), and the table
/// cannot print or leak a token.
#[derive(Clone, Debug, Default)]
pub struct Auth {
    tokens: HashMap<TokenDigest, Caller>,
}

/// The SHA-256 of a bearer token.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct TokenDigest([u8; 32]);

impl TokenDigest {
    fn of(token: &str) -> Self {
        let d = ring::digest::digest(&ring::digest::SHA256, token.as_bytes());
        TokenDigest(d.as_ref().try_into().expect("SHA-256 is 32 bytes"))
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AuthFile {
    #[serde(default)]
    token: Vec<TokenEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TokenEntry {
    token: String,
    user: String,
    role: Role,
}

impl Auth {
    /// Open mode: no tokens.
    pub fn open() -> Self {
        Self::default()
    }

    /// Whether no tokens are configured.
    pub fn is_open(&self) -> bool {
        self.tokens.is_empty()
    }

    fn insert(&mut self, token: String, user: String, role: Role) -> Result<(), String> {
        if token.is_empty() || user.is_empty() {
            return Err("tokens and user names must not be empty".into());
        }
        if self
            .tokens
            .insert(TokenDigest::of(&token), Caller { user, role })
            .is_some()
        {
            return Err("a token is listed twice".into());
        }
        Ok(())
    }

    /// Reads the TOML token file.
    pub fn from_file(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let f: AuthFile = toml::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut a = Auth::default();
        for t in f.token {
            a.insert(t.token, t.user, t.role)
                .map_err(|e| format!("{}: {e}", path.display()))?;
        }
        Ok(a)
    }

    /// Parses `TOKEN=user:role,...` (the `NAADF_TOKENS` form).
    pub fn from_env_value(value: &str) -> Result<Self, String> {
        let mut a = Auth::default();
        for item in value.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (token, rest) = item
                .split_once('=')
                .ok_or_else(|| format!("NAADF_TOKENS entry '{item}' is not TOKEN=user:role"))?;
            let (user, role) = rest
                .split_once(':')
                .ok_or_else(|| format!("NAADF_TOKENS entry for user '{rest}' lacks ':role'"))?;
            let role = Role::parse(role)
                .ok_or_else(|| format!("unknown role '{role}' (viewer, editor, admin, render-node)"))?;
            a.insert(token.into(), user.into(), role)?;
        }
        Ok(a)
    }

    /// Adds the tokens of another table (file plus environment).
    pub fn merge(&mut self, other: Auth) -> Result<(), String> {
        for (digest, caller) in other.tokens {
            if self.tokens.insert(digest, caller).is_some() {
                return Err("a token is listed twice".into());
            }
        }
        Ok(())
    }

    /// The caller of a request, from its `authorization: Bearer <token>` metadata.
    pub fn caller(&self, md: &MetadataMap) -> Result<Caller, Status> {
        let token = match md.get("authorization") {
            None => None,
            Some(v) => {
                let v = v
                    .to_str()
                    .map_err(|_| Status::unauthenticated("the authorization header is not ASCII"))?;
                let t = v
                    .strip_prefix("Bearer ")
                    .ok_or_else(|| Status::unauthenticated("the authorization header must be 'Bearer <token>'"))?;
                Some(t.trim())
            }
        };
        if self.is_open() {
            return Ok(Caller {
                user: token.filter(|t| !t.is_empty()).unwrap_or("anonymous").to_owned(),
                role: Role::Admin,
            });
        }
        let token =
            token.ok_or_else(|| Status::unauthenticated("this server needs 'authorization: Bearer <token>'"))?;
        self.tokens
            .get(&TokenDigest::of(token))
            .cloned()
            .ok_or_else(|| Status::unauthenticated("unknown token"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn md(token: Option<&str>) -> MetadataMap {
        let mut m = MetadataMap::new();
        if let Some(t) = token {
            m.insert("authorization", t.parse().unwrap());
        }
        m
    }

    #[test]
    fn tokens_map_to_users_and_roles() {
        let a = Auth::from_env_value("v1=val:viewer, e1=ed:editor,a1=root:admin").unwrap();
        let c = a.caller(&md(Some("Bearer e1"))).unwrap();
        assert_eq!((c.user.as_str(), c.role), ("ed", Role::Editor));
        assert!(c.require_editor().is_ok() && c.require_admin("x").is_err());
        let v = a.caller(&md(Some("Bearer v1"))).unwrap();
        assert_eq!(v.require_editor().unwrap_err().code(), tonic::Code::PermissionDenied);
        assert_eq!(a.caller(&md(None)).unwrap_err().code(), tonic::Code::Unauthenticated);
        assert_eq!(
            a.caller(&md(Some("Bearer nope"))).unwrap_err().code(),
            tonic::Code::Unauthenticated
        );
        assert_eq!(
            a.caller(&md(Some("e1"))).unwrap_err().code(),
            tonic::Code::Unauthenticated
        );
        assert!(Auth::from_env_value("x=y").is_err());
        assert!(Auth::from_env_value("x=y:king").is_err());
        assert!(Auth::from_env_value("x=y:admin,x=z:viewer").is_err());
    }

    #[test]
    fn the_file_form_parses_and_open_mode_admits_everyone() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("auth.toml");
        std::fs::write(&p, "[[token]]\ntoken = \"t\"\nuser = \"u\"\nrole = \"render-node\"\n").unwrap();
        let a = Auth::from_file(&p).unwrap();
        assert_eq!(a.caller(&md(Some("Bearer t"))).unwrap().role, Role::RenderNode);
        std::fs::write(&p, "[[token]]\ntoken = \"t\"\n").unwrap();
        assert!(Auth::from_file(&p).is_err());
        let open = Auth::open();
        assert_eq!(open.caller(&md(None)).unwrap().user, "anonymous");
        assert_eq!(open.caller(&md(Some("Bearer bob"))).unwrap().user, "bob");
    }

    /// The table keeps digests only: no token can be read back from it (in a log line of
    /// its `Debug`, say), and a lookup compares digests, not the secret itself.
    #[test]
    fn the_table_holds_no_token_in_the_clear() {
        let secret = "s3cret-token-abcdefgh";
        let mut a = Auth::from_env_value(&format!("{secret}=alice:editor")).unwrap();
        a.merge(Auth::from_env_value("other-token=bob:viewer").unwrap())
            .unwrap();
        let shown = format!("{a:?}");
        assert!(!shown.contains(secret) && !shown.contains("other-token"), "{shown}");
        assert_eq!(a.caller(&md(Some(&format!("Bearer {secret}")))).unwrap().user, "alice");
        // A prefix of a valid token is as unknown as any other guess.
        assert!(a.caller(&md(Some("Bearer s3cret-token"))).is_err());
        assert!(a.merge(Auth::from_env_value("other-token=eve:admin").unwrap()).is_err());
    }
}
