"""A robot's connection settings, from the connection bar's Security button: the CA file that signed its
certificate, a client certificate and key for a robot that asks for one, whether it checks a rosauth
secret, and the secret itself (kept by :class:`~rcon_core.app.secret_store.SecretStore`, never in
``app.json``).  The files are checked when saved, so a typo is named here and not as a failed link later.
"""

from __future__ import annotations

from qtpy import QtCore, QtWidgets

from rcon_core.app.config import AppConfig
from rcon_core.app.secret_store import SecretStore
from rcon_core.bridge import LinkSettingsError
from rcon_core.bridge.secure import ssl_context

#: (key, label, placeholder, tooltip)
FILE_FIELDS = (
    ("ca_file", "CA file", "none: the system's CAs", "the certificate authority (PEM) that signed the robot's "
                                                      "certificate (wss:// only)"),
    ("client_cert", "Client certificate", "none", "only for a robot that asks for one (PEM)"),
    ("client_key", "Client key", "none", "the client certificate's private key (PEM)"),
)


class PathField(QtWidgets.QWidget):
    """A file path: typed, or chosen with a file dialog."""

    def __init__(self, name: str, placeholder: str, tooltip: str, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.edit = QtWidgets.QLineEdit()
        self.edit.setObjectName(f"{name}Field")
        self.edit.setPlaceholderText(placeholder)
        self.edit.setToolTip(tooltip)
        self.edit.setClearButtonEnabled(True)
        self.choose = QtWidgets.QPushButton("Choose…")
        self.choose.setObjectName(f"{name}Choose")
        self.choose.clicked.connect(self._choose)
        row = QtWidgets.QHBoxLayout(self)
        row.setContentsMargins(0, 0, 0, 0)
        row.addWidget(self.edit, 1)
        row.addWidget(self.choose)
        self.dialog: QtWidgets.QFileDialog | None = None

    def _choose(self) -> None:
        dialog = QtWidgets.QFileDialog(self, "Choose a PEM file", self.edit.text() or "")
        dialog.setOption(QtWidgets.QFileDialog.Option.DontUseNativeDialog, True)
        dialog.setFileMode(QtWidgets.QFileDialog.FileMode.ExistingFile)
        dialog.setNameFilters(["PEM files (*.pem *.crt *.cer *.key)", "All files (*)"])
        dialog.fileSelected.connect(self.edit.setText)
        self.dialog = dialog
        dialog.open()

    def text(self) -> str:
        return self.edit.text().strip()


class LinkSettingsDialog(QtWidgets.QDialog):
    """Edit and save one robot's connection settings; ``accepted`` once they are saved."""

    def __init__(self, url: str, config: AppConfig, secrets: SecretStore,
                 parent: QtWidgets.QWidget | None = None, *, ask_secret: bool = False) -> None:
        super().__init__(parent)
        self.setObjectName("linkSettings")
        self.setWindowTitle("Connection settings")
        self.url, self.config, self.secrets = url, config, secrets
        saved = config.robot_settings(url)
        has_secret = secrets.get(url) is not None

        title = QtWidgets.QLabel(url)
        title.setObjectName("linkSettingsUrl")
        title.setWordWrap(True)
        form = QtWidgets.QFormLayout()
        self.paths: dict[str, PathField] = {}
        for key, label, placeholder, tooltip in FILE_FIELDS:
            field = PathField(key, placeholder, tooltip)
            field.edit.setText(saved[key])
            self.paths[key] = field
            form.addRow(label, field)
        self.use_auth = QtWidgets.QCheckBox("The robot checks a rosauth secret")
        self.use_auth.setObjectName("useAuth")
        self.use_auth.setChecked(saved["auth"] or ask_secret)
        self.secret = QtWidgets.QLineEdit()
        self.secret.setObjectName("secretField")
        self.secret.setEchoMode(QtWidgets.QLineEdit.EchoMode.Password)
        self.secret.setPlaceholderText("unchanged (a secret is stored)" if has_secret else "the robot's secret")
        self.where = QtWidgets.QLabel(secrets.where)
        self.where.setObjectName("secretWhere")
        self.where.setWordWrap(True)
        form.addRow(self.use_auth)
        form.addRow("Secret", self.secret)
        form.addRow(self.where)
        self.problem = QtWidgets.QLabel()
        self.problem.setObjectName("linkSettingsProblem")
        self.problem.setProperty("role", "problem")
        self.problem.setWordWrap(True)
        if ask_secret and not has_secret:
            self.problem.setText("This robot checks a secret: enter it to connect.")
        self.use_auth.toggled.connect(self._auth_toggled)
        self._auth_toggled(self.use_auth.isChecked())

        buttons = QtWidgets.QDialogButtonBox()
        self.save_button = buttons.addButton("Save and connect", QtWidgets.QDialogButtonBox.ButtonRole.AcceptRole)
        self.save_button.setObjectName("saveLinkSettings")
        self.save_button.setProperty("primary", True)
        cancel = buttons.addButton(QtWidgets.QDialogButtonBox.StandardButton.Cancel)
        cancel.setObjectName("cancelLinkSettings")
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)

        col = QtWidgets.QVBoxLayout(self)
        col.addWidget(title)
        col.addLayout(form)
        col.addWidget(self.problem)
        col.addWidget(buttons)
        room = parent.window().width() - 40 if parent is not None else 640
        self.setMinimumWidth(max(360, min(640, room)))
        if ask_secret:
            QtCore.QTimer.singleShot(0, self.secret.setFocus)

    def _auth_toggled(self, on: bool) -> None:
        self.secret.setEnabled(on)
        self.where.setEnabled(on)

    def accept(self) -> None:
        values = {key: field.text() for key, field in self.paths.items()}
        if any(values.values()):
            try:
                ssl_context(values["ca_file"] or None, values["client_cert"] or None, values["client_key"] or None)
            except LinkSettingsError as exc:
                self.problem.setText(str(exc))
                return
        secret = self.secret.text()
        auth = self.use_auth.isChecked()
        if auth and not secret and self.secrets.get(self.url) is None:
            self.problem.setText("Enter the robot's secret, or untick the rosauth box.")
            return
        self.config.set_robot_settings(self.url, {**values, "auth": auth})
        if auth and secret:
            self.secrets.set(self.url, secret)
        elif not auth:
            self.secrets.forget(self.url)
        self.secret.clear()
        super().accept()
