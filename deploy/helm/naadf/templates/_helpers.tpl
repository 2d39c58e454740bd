{{/* The chart name. */}}
{{- define "naadf.name" -}}
{{- default .Chart.Name .Values.nameOverride | trunc 63 | trimSuffix "-" -}}
{{- end -}}

{{/* The resource name prefix: fullnameOverride, or `<release>-<chart>` (the release name
alone when it already contains the chart name). */}}
{{- define "naadf.fullname" -}}
{{- if .Values.fullnameOverride -}}
{{- .Values.fullnameOverride | trunc 63 | trimSuffix "-" -}}
{{- else -}}
{{- $name := default .Chart.Name .Values.nameOverride -}}
{{- if contains $name .Release.Name -}}
{{- .Release.Name | trunc 63 | trimSuffix "-" -}}
{{- else -}}
{{- printf "%s-%s" .Release.Name $name | trunc 63 | trimSuffix "-" -}}
{{- end -}}
{{- end -}}
{{- end -}}

{{- define "naadf.chart" -}}
{{- printf "%s-%s" .Chart.Name .Chart.Version | replace "+" "_" | trunc 63 | trimSuffix "-" -}}
{{- end -}}

{{/* Labels of every resource. */}}
{{- define "naadf.labels" -}}
helm.sh/chart: {{ include "naadf.chart" . }}
{{ include "naadf.selectorLabels" . }}
app.kubernetes.io/version: {{ .Chart.AppVersion | quote }}
app.kubernetes.io/managed-by: {{ .Release.Service }}
{{- end -}}

{{- define "naadf.selectorLabels" -}}
app.kubernetes.io/name: {{ include "naadf.name" . }}
app.kubernetes.io/instance: {{ .Release.Name }}
{{- end -}}

{{/* Names of the parts. */}}
{{- define "naadf.serverName" -}}{{ include "naadf.fullname" . }}{{- end -}}
{{- define "naadf.renderNodeName" -}}{{ printf "%s-render-node" (include "naadf.fullname" .) | trunc 63 | trimSuffix "-" }}{{- end -}}
{{- define "naadf.relayName" -}}{{ printf "%s-relay" (include "naadf.fullname" .) | trunc 63 | trimSuffix "-" }}{{- end -}}

{{/* The Secret with the tokens. */}}
{{- define "naadf.tokensSecret" -}}
{{- if .Values.tokens.create -}}
{{- printf "%s-tokens" (include "naadf.fullname" .) -}}
{{- else -}}
{{- required "tokens.existingSecret is empty: name a Secret with the tokens, or set tokens.create" .Values.tokens.existingSecret -}}
{{- end -}}
{{- end -}}

{{/* The TLS Secret. */}}
{{- define "naadf.tlsSecret" -}}
{{- default (printf "%s-tls" (include "naadf.fullname" .)) .Values.tls.secretName -}}
{{- end -}}

{{/* The URL render nodes dial: the server Service. */}}
{{- define "naadf.serverUrl" -}}
{{- printf "%s://%s:%v" (ternary "https" "http" .Values.tls.enabled) (include "naadf.serverName" .) .Values.server.service.grpcPort -}}
{{- end -}}

{{/* The URL relays mirror: relay.upstream, or the server Service. */}}
{{- define "naadf.relayUpstream" -}}
{{- default (include "naadf.serverUrl" .) .Values.relay.upstream -}}
{{- end -}}

{{/* The relays' TLS Secret: relay.tls.secretName, or the server's. */}}
{{- define "naadf.relayTlsSecret" -}}
{{- default (include "naadf.tlsSecret" .) .Values.relay.tls.secretName -}}
{{- end -}}

{{/* The relays' image: relay.image, each empty field taken from server.image. */}}
{{- define "naadf.relayImage" -}}
{{- $s := .Values.server.image -}}
{{- $r := .Values.relay.image -}}
{{- dict "repository" (default $s.repository $r.repository) "tag" (default $s.tag $r.tag) "pullPolicy" (default $s.pullPolicy $r.pullPolicy) | toJson -}}
{{- end -}}

{{/* An image reference: repository:tag, the tag defaulting to the appVersion. */}}
{{- define "naadf.image" -}}
{{- printf "%s:%s" .image.repository (default .root.Chart.AppVersion .image.tag) -}}
{{- end -}}
